#pragma once
// Run-time changes of the elements (docs/method.md, "Per-frame input"): stiffnesses, enabled
// flags and the pin set, each validated before anything changes, with L and its factors
// following the changed weights as one GlobalSystem::apply (rank updates or, past its price, a
// new assembly and factorization); and the same changes when a checkpoint is restored. The
// driver books the jump of H these cause as an event; the contact set's changes are
// ContactResolver's. A batch changes one scene's elements through the same code (InputScope: its
// indices and messages).
#include "backend/backend.hpp"
#include "driver/input_scope.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"

#include <stabint/types.hpp>

#include <cstdint>
#include <vector>

namespace stabint {

class Forcing;

class ElementChanges {
 public:
  /// Element indices and messages are the scope's (the whole scene by default). `forcing` follows
  /// the pin set (its ramps go with their pins).
  ElementChanges(SceneData& scene, Forcing& forcing, GlobalSystem& system, Backend& backend, InputScope scope = {});

  /// The block of an element kind, by the type's identifier (the names agree by construction);
  /// InvalidInputError for a value that is no ElementKind or a kind without a type.
  int block(ElementKind kind) const;
  /// InvalidInputError, naming `call`, for an element index out of the scope's range of the block.
  void checkIndex(int block, int index, const char* call) const;
  /// Whether element `index` of `kind` is enabled (elementEnabled).
  bool enabled(ElementKind kind, int index) const;

  /// setElementStiffness (`stiffness` given) or setElementEnabled (`enabled`) of `indices`:
  /// everything is validated before L changes; a system that does not factor puts the old
  /// stiffnesses and flags back, and L and the factors as they were (bit for bit), and throws.
  void change(ElementKind kind, std::vector<int> indices, const double* stiffness, bool enabled);

  /// A new pin set (validated first: nothing changes when it throws): the element blocks and
  /// the backends follow, and L and the factors by a diagonal term per particle whose pin
  /// stiffness changed (GlobalSystem::apply). `inserted`: the index of a pin inserted before
  /// others (a grab in a batch's scene that is not the last), whose ramps and enabled flags move
  /// with their pins; -1 when every pin keeps its index.
  void changePins(const std::vector<Pin>& pins, int inserted = -1);

  /// A saved element state (SceneData::elementState; counts checked by the caller): its pin set,
  /// stiffnesses and enabled flags. Elements that differ are changed as change() would, without an
  /// event (H* is restored). With `contact_flags` the contact block (`contact_block`) takes those
  /// flags and L and the factors are left to the caller, who assembles and factors them again.
  void restore(const ElementState& state, int contact_block, const std::vector<std::uint8_t>* contact_flags);

 private:
  void addTerm(GlobalSystem::WeightChange& change, int block, int e, double w_old) const;

  SceneData& scene_;
  Forcing& forcing_;
  GlobalSystem& system_;
  Backend& backend_;
  InputScope scope_;
};

}  // namespace stabint
