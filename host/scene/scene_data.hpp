#pragma once
// SceneData: the validated scene in the form both backends consume. Built once per Simulator;
// everything here is immutable afterwards except through the time-dependent forcing queries.
#include "elements/element_type.hpp"

#include <stabint/scene.hpp>

#include <Eigen/Core>

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

class SceneData {
 public:
  /// Validates (validateScene) and precomputes. Throws InvalidInputError.
  explicit SceneData(const Scene& scene);

  int numParticles() const { return n_; }
  const Scene& scene() const { return scene_; }
  const Eigen::VectorXd& masses() const { return scene_.masses; }
  /// One block per element type, in the order of elementTypes() (empty ones included).
  const std::vector<ElementBlock>& blocks() const { return blocks_; }
  const ContributionCsr& csr() const { return csr_; }

  /// External force m_j g + sum of force fields at time t, `n by 3`.
  void externalForces(double t, Eigen::MatrixX3d& out) const;
  /// Pin targets q(t), `#pins by 3`.
  void pinTargets(double t, Eigen::MatrixX3d& out) const;
  /// True when pins move or force fields change with time (the blend then books forcing).
  bool hasTimeDependentForcing() const { return time_dependent_forcing_; }
  bool hasTimeDependentForceFields() const { return time_dependent_fields_; }
  bool hasMovingPins() const { return moving_pins_; }

 private:
  Scene scene_;
  int n_ = 0;
  std::vector<ElementBlock> blocks_;
  ContributionCsr csr_;
  bool moving_pins_ = false;
  bool time_dependent_fields_ = false;
  bool time_dependent_forcing_ = false;
};

}  // namespace stabint
