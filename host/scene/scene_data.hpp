#pragma once
// SceneData: the validated scene in the form both backends consume. Built once per Simulator;
// everything here is immutable afterwards except through the time-dependent forcing queries.
#include <stabint/scene.hpp>

#include <Eigen/Core>

#include <vector>

namespace stabint {

/// A tet with its rest shape precomputed: F = Ds * dm_inverse where
/// Ds = [x1-x0, x2-x0, x3-x0]; weight = stiffness * rest volume.
struct TetRest {
  std::array<int, 4> vertices;
  Eigen::Matrix3d dm_inverse;
  double weight;
};

/// Per-vertex list (CSR) of the element contributions A_e^T p_e that land on that vertex. The
/// contributions are numbered: springs first (2 per spring: end a, then end b), then tets (4 per
/// tet, vertex order), then pins (1 per pin). The gather sums them in list order, so the
/// right-hand side is deterministic.
struct ContributionCsr {
  std::vector<int> offsets;        // size n + 1
  std::vector<int> contributions;  // contribution indices, sorted ascending per vertex
  int numContributions = 0;
  int springBase = 0;
  int tetBase = 0;
  int pinBase = 0;
};

class SceneData {
 public:
  /// Validates (validateScene) and precomputes. Throws InvalidInputError.
  explicit SceneData(const Scene& scene);

  int numParticles() const { return n_; }
  const Scene& scene() const { return scene_; }
  const Eigen::VectorXd& masses() const { return scene_.masses; }
  const std::vector<Spring>& springs() const { return scene_.springs; }
  const std::vector<TetRest>& tets() const { return tets_; }
  const std::vector<Pin>& pins() const { return scene_.pins; }
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
  std::vector<TetRest> tets_;
  ContributionCsr csr_;
  bool moving_pins_ = false;
  bool time_dependent_fields_ = false;
  bool time_dependent_forcing_ = false;
};

}  // namespace stabint
