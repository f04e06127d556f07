#pragma once
// SceneData: the validated scene in the form both backends consume, built once per Simulator or
// batch: the element blocks and the contribution lists. The owner of the element set of a running
// simulation: element changes rewrite two parts of it in place, where the kernels' layout has
// them (a one-element change costs that element, not a copy of the blocks), each through its own
// calls and a version the backends key their caches on (docs/method.md, "Per-frame input"):
// - element stiffnesses and enabled flags: the params in place (ElementBlock::params_revision);
// - the pin set (grab, release): the pin block (ElementBlock::revision) and the contribution
//   lists rebuilt.
// The rest is fixed. Those changes as a value are its ElementState (elementState()), one part of
// the state a checkpoint holds (state/checkpoint.hpp: CheckpointData); the other parts are the
// driver's (positions, velocities, each scene's SceneBook, the Forcing: pin targets, forces and
// collider motion) and the backends' slots. The factors (GlobalSystem) follow the element weights
// through GlobalSystem::apply.
#include "elements/element_type.hpp"
#include "scene/scene_batch.hpp"

#include <stabint/scene.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace stabint {

/// Per-vertex list (CSR) of the element contributions w_e A_e^T p_e that land on that vertex.
/// Contributions are numbered block by block in the order of elementTypes(), element by element,
/// vertex tuple order within an element (ElementBlock::contribution_base). The gather sums each
/// vertex's list in that order, so the right-hand side is deterministic.
struct ContributionCsr {
  std::vector<int> offsets;        // size n + 1
  std::vector<int> contributions;  // contribution indices, sorted ascending per vertex
  int numContributions = 0;
};

/// The elements as run-time changes left them, as one value: the pin set (the scene's, grabbed
/// and released) and per element block, in the order of elementTypes(), each element's stiffness
/// (0 for a type without one) and enabled flag. SceneData::elementState gives it; a checkpoint
/// saves it and ElementChanges::restore puts it back.
struct ElementState {
  std::vector<Pin> pins;
  std::vector<std::vector<double>> stiffness;
  std::vector<std::vector<std::uint8_t>> enabled;
};

class SceneData final {
 public:
  /// Validates (validateScene) and precomputes. Throws InvalidInputError.
  explicit SceneData(const Scene& scene);

  int numParticles() const { return n_; }
  const Scene& scene() const { return scene_; }
  const Eigen::VectorXd& masses() const { return scene_.masses; }
  /// One block per element type, in the order of elementTypes() (empty ones included).
  const std::vector<ElementBlock>& blocks() const { return blocks_; }
  const ContributionCsr& csr() const { return csr_; }

  // ---- changes of the element set (grab and release) -----------------------------------------
  /// Replaces the pins (validated like a scene's; InvalidInputError naming the pin, nothing
  /// changed then) and rebuilds the pin block and the contribution lists. The forcing, the
  /// backends (Backend::elementsChanged) and the global system must then be told.
  void setPins(const std::vector<Pin>& pins);

  // ---- element stiffness and enabled flags (Simulator::setElementStiffness, setElementEnabled) --
  /// Index of `type`'s block in blocks().
  int blockIndex(const ElementType& type) const;
  /// Sets element `element` of block `block`'s stiffness in the scene and its params (checked by
  /// the caller). Its weight stays 0 while it is disabled.
  void setElementStiffness(int block, int element, double stiffness);
  /// A disabled element keeps its stiffness and has weight 0.
  void setElementEnabled(int block, int element, bool enabled);
  bool elementEnabled(int block, int element) const {
    const std::vector<std::uint8_t>& flags = enabled_[static_cast<std::size_t>(block)];
    return flags.empty() || flags[static_cast<std::size_t>(element)] != 0;
  }
  /// Writes `count` params of element `element` of block `block` from index `first` >= 1 on (the
  /// weight, params[0], stays the set's): a pair's step geometry that the contact broad phase
  /// derives (docs/method.md, "Contact", "The pair's half-space"). Not part of ElementState: it is
  /// a function of the state, written again after every step and by a restore.
  void setElementParams(int block, int element, int first, const double* values, int count);
  /// The pins, stiffnesses and enabled flags as they are now.
  ElementState elementState() const;
  /// w_e as the global matrix has it: params[P e] (0 for a disabled element).
  double elementWeight(int block, int element) const {
    const ElementBlock& b = blocks_[static_cast<std::size_t>(block)];
    return b.params[static_cast<std::size_t>(b.type->shape().params) * static_cast<std::size_t>(element)];
  }
  /// w_e while the element is enabled, whether it is or not, for a block whose type gives
  /// ElementType::weightsFromBlocks (contact: a pair's weight in the contact set).
  double enabledWeight(int block, int element) const;

 private:
  void buildBlocks();
  void numberContributions();
  // Zeroes the weights of the disabled elements of a freshly built block.
  void applyEnabled(std::size_t block);
  // Element `element`'s params from its type, with weights_' weight where the block has them.
  void writeElementParams(std::size_t block, int element);
  // Element `element`'s params were rewritten in place: a new params revision, and the element
  // in the block's log (ElementBlock::changed_params).
  void paramsChanged(ElementBlock& block, int element);

  Scene scene_;
  int n_ = 0;
  std::vector<ElementBlock> blocks_;
  ContributionCsr csr_;
  std::vector<std::vector<std::uint8_t>> enabled_;  // per block; empty: all enabled
  // Per block: the weights ElementType::weightsFromBlocks gave (empty: the type's own params).
  std::vector<std::vector<double>> weights_;
};

}  // namespace stabint
