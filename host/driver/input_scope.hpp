#pragma once
// What one call of per-frame input or of an element change addresses (docs/method.md,
// "Per-frame input"): the whole scene for a Simulator, one scene of a batch for BatchSimulator.
// FrameInput and ElementChanges check the caller's indices against the scope's ranges and shift
// them to the SceneData's, so both drivers run the same checks, ramps and changes.
#include "elements/element_type.hpp"
#include "scene/scene_batch.hpp"
#include "scene/scene_data.hpp"

#include <cstddef>
#include <string>

namespace stabint {

/// The caller's indices [0, count) are the SceneData's [first, first + count).
struct InputRange {
  int first = 0;
  int count = 0;
};

class InputScope {
 public:
  /// The whole scene: indices are the SceneData's, messages as Simulator's.
  InputScope() = default;
  /// Scene `scene` of a batch, at `segment` (which must outlive the scope): indices count from
  /// the segment's first particle, pin, collider and element, and every message starts with
  /// "<call>: scene <scene>: ".
  InputScope(const SceneSegment& segment, int scene, const char* call)
      : segment_(&segment), where_(std::string(call) + ": scene " + std::to_string(scene) + ": ") {}

  InputRange particles(const SceneData& data) const {
    return segment_ ? InputRange{segment_->first_particle, segment_->num_particles}
                    : InputRange{0, data.numParticles()};
  }
  /// Of block `block` (a segment's per-type ranges are per block: blocks follow elementTypes()).
  InputRange elements(const SceneData& data, int block) const {
    const std::size_t b = static_cast<std::size_t>(block);
    return segment_ ? InputRange{segment_->first_element[b], segment_->num_elements[b]}
                    : InputRange{0, data.blocks()[b].count};
  }
  /// The pins are the pin type's block.
  InputRange pins(const SceneData& data) const {
    return segment_ ? elements(data, data.blockIndex(pinElementType()))
                    : InputRange{0, static_cast<int>(data.scene().pins.size())};
  }
  InputRange colliders(const SceneData& data) const {
    return segment_ ? InputRange{segment_->first_collider, segment_->num_colliders}
                    : InputRange{0, static_cast<int>(data.scene().colliders.size())};
  }

  /// A message's prefix: a batch scene's "<call>: scene <s>: "; for the whole scene "<call>: "
  /// where Simulator's messages name their call (`call` given), else nothing.
  std::string where(const char* call = nullptr) const {
    if (!where_.empty()) return where_;
    return call ? std::string(call) + ": " : std::string();
  }

 private:
  const SceneSegment* segment_ = nullptr;
  std::string where_;
};

}  // namespace stabint
