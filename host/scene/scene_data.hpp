#pragma once
// SceneData: the validated scene in the form both backends consume, built once per Simulator or
// batch. Not immutable: a running simulation's input changes three parts of it, each through its
// own calls and a version the backends key their caches on (docs/method.md, "Per-frame input"):
// - the forcing: pin targets, external forces and collider motion as ramps (forcingVersion,
//   forcesVersion; backends evaluate it through pinTarget and externalForces);
// - element stiffnesses and enabled flags: the params in place (ElementBlock::params_revision);
// - the pin set (grab, release): the pin block and the contribution lists rebuilt (layoutVersion).
// The rest is fixed. The other owners of the running state are the driver (positions,
// velocities, each scene's SceneBook), the backends' slots and the factors (GlobalSystem), which
// follow the element weights through GlobalSystem::apply.
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

class SceneData final : public RunningScene {
 public:
  /// Validates (validateScene) and precomputes. Throws InvalidInputError.
  explicit SceneData(const Scene& scene);

  int numParticles() const { return n_; }
  const Scene& scene() const override { return scene_; }
  const Eigen::VectorXd& masses() const { return scene_.masses; }
  /// One block per element type, in the order of elementTypes() (empty ones included).
  const std::vector<ElementBlock>& blocks() const { return blocks_; }
  const ContributionCsr& csr() const { return csr_; }

  /// External force m_j g + sum of force fields + the user's forces at time t, `n by 3`.
  void externalForces(double t, Eigen::MatrixX3d& out) const;
  /// Target of pin i at time t: the user's ramp once one was set, else the scene's law q(t).
  Eigen::Vector3d pinTarget(int pin, double t) const override;
  /// Pin targets q(t), `#pins by 3`.
  void pinTargets(double t, Eigen::MatrixX3d& out) const;
  /// True when pins move or force fields change with time (the blend then books forcing).
  bool hasTimeDependentForcing() const { return hasMovingPins() || hasTimeDependentForces() || hasMovingColliders(); }
  /// A collider moves by its scene velocity or was driven at run time: the contact params depend
  /// on time and the collider does work.
  bool hasMovingColliders() const override { return moving_colliders_ || driven_colliders_ > 0; }
  /// Where collider c's reference point (Collider::center) is at time t, and how fast it moves
  /// there (over the step ending at t when t ends a ramp).
  Eigen::Vector3d colliderPosition(int collider, double t) const override;
  Eigen::Vector3d colliderVelocity(int collider, double t) const;
  /// The collider's geometry (host/elements/contact.hpp) at time t.
  void colliderGeometry(int collider, double t, double* geometry) const;
  /// Pin targets or external forces that may change with time: a pin law that moves, a force
  /// field that varies, or any user ramp (their params are then evaluated per time).
  bool hasTimeDependentForces() const { return time_dependent_fields_ || user_forces_.active; }
  bool hasMovingPins() const override { return moving_pins_ || ramped_pins_ > 0; }
  /// setExternalForces was called: the scene no longer conserves momentum.
  bool hasUserForces() const { return user_forces_.active; }
  /// Per segment of `segments` (a batch's scenes; a Simulator's one scene): whether its forcing
  /// differs anywhere between t0 and t1, so that a step over [t0, t1] does work through it: a
  /// moving or ramped pin on its particles, a time-dependent force field or a user-force ramp
  /// acting on them, one of its colliders moving. False once every ramp has reached its end value
  /// and no law moves.
  std::vector<char> forcingChangesDuring(double t0, double t1, const std::vector<SceneSegment>& segments) const;

  // ---- input of a running simulation: linear ramps over the next step ------------------------
  /// Pin `pin`'s target moves linearly from its value at t0 to `target` at t1 and stays there;
  /// the scene's law for that pin is no longer used.
  void rampPinTarget(int pin, const Eigen::Vector3d& target, double t0, double t1);
  /// The user's per-particle forces move linearly from their value at t0 to `forces` at t1 and
  /// stay there (zero before the first call).
  void rampUserForces(const Eigen::MatrixX3d& forces, double t0, double t1);
  /// The same for rows first.. of the user's forces only (one scene of a batch); the other rows
  /// go on to the values they were given. Within a ramp over the same [t0, t1] (scenes set one
  /// after another before a step) it costs the rows it sets, not the batch's.
  void rampUserForceRows(int first, const Eigen::MatrixX3d& forces, double t0, double t1);
  /// Collider `collider` moves linearly from its position at t0 to `position` at t1 and stays
  /// there; its scene velocity is no longer used.
  void rampColliderPosition(int collider, const Eigen::Vector3d& position, double t0, double t1);
  /// Collider `collider` moves with `velocity` from its position at t0 on.
  void setColliderVelocity(int collider, const Eigen::Vector3d& velocity, double t0);
  /// Incremented by every change of the forcing (ramps, restore), so cached forcing is refreshed.
  int forcingVersion() const { return forcing_version_; }
  /// Incremented by every change of what externalForces gives (user-force ramps, restore); the
  /// changes of pins, colliders and elements, which move forcingVersion, leave it, so that one
  /// scene's element change in a batch does not evaluate every particle's forces again.
  int forcesVersion() const { return forces_version_; }

  // ---- changes of the element set (grab and release) -----------------------------------------
  /// Replaces the pins (validated like a scene's; InvalidInputError naming the pin, nothing
  /// changed then) and rebuilds the pin block and the contribution lists. Ramps of pins that keep
  /// their index and vertex stay; the others are dropped. Backends must then be told
  /// (Backend::elementsChanged), and the global system updated.
  void setPins(const std::vector<Pin>& pins);
  /// Incremented by every setPins.
  int layoutVersion() const { return layout_version_; }

  // ---- element stiffness and enabled flags (Simulator::setElementStiffness, setElementEnabled) --
  /// Index of `type`'s block in blocks().
  int blockIndex(const ElementType& type) const override;
  /// Sets element `element` of block `block`'s stiffness in the scene and its params (checked by
  /// the caller). Its weight stays 0 while it is disabled.
  void setElementStiffness(int block, int element, double stiffness);
  /// A disabled element keeps its stiffness and has weight 0.
  void setElementEnabled(int block, int element, bool enabled);
  bool elementEnabled(int block, int element) const override {
    const std::vector<std::uint8_t>& flags = enabled_[static_cast<std::size_t>(block)];
    return flags.empty() || flags[static_cast<std::size_t>(element)] != 0;
  }
  bool elementEnabled(const ElementType& type, int element) const { return elementEnabled(blockIndex(type), element); }
  /// w_e as the global matrix has it: params[P e] (0 for a disabled element).
  double elementWeight(int block, int element) const {
    const ElementBlock& b = blocks_[static_cast<std::size_t>(block)];
    return b.params[static_cast<std::size_t>(b.type->shape().params) * static_cast<std::size_t>(element)];
  }

  /// The mutable forcing, for checkpoints: everything the ramps changed.
  struct Ramp {
    double t0 = 0.0, t1 = 0.0;
    Eigen::MatrixX3d start, end;  // values at t0 and t1 (1 by 3 for a pin, n by 3 for forces)
    bool active = false;
    /// Exactly `start` at t0 and `end` at and after t1.
    Eigen::MatrixX3d at(double t) const;
  };
  /// A collider's translation: from `start` at t0 linearly to `end` at t1 (none when t1 == t0),
  /// then on with `velocity`. The scene's law center + velocity t is {0, 0, center, center,
  /// velocity}; `driven` tells a motion set at run time.
  struct ColliderMotion {
    double t0 = 0.0, t1 = 0.0;
    Eigen::Vector3d start = Eigen::Vector3d::Zero(), end = Eigen::Vector3d::Zero();
    Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
    bool driven = false;
    /// Exactly `start` at t0 and `end` at t1; the scene's law bit for bit (center + t velocity).
    Eigen::Vector3d at(double t) const;
    /// The ramp's velocity up to t1 (so a step ending at t1 sees the velocity it moved with),
    /// `velocity` after it.
    Eigen::Vector3d velocityAt(double t) const;
    bool movesDuring(double a, double b) const;
  };
  struct ForcingState {
    std::vector<Ramp> pins;  // one per pin; inactive: the scene's law
    Ramp user_forces;
    std::vector<ColliderMotion> colliders;  // one per collider; empty: the scene's laws
  };
  ForcingState forcingState() const { return ForcingState{pin_ramps_, user_forces_, collider_motion_}; }
  /// The user's forces' ramp alone (inactive before the first rampUserForces).
  const Ramp& userForces() const { return user_forces_; }
  /// Replaces the forcing with a saved one of the same scene (sizes checked by the caller).
  void setForcingState(const ForcingState& state);

 private:
  void buildBlocks();
  void numberContributions();
  // Zeroes the weights of the disabled elements of a freshly built block.
  void applyEnabled(std::size_t block);
  // Element `element`'s params were rewritten in place: a new params revision, and the element
  // in the block's log (ElementBlock::changed_params).
  void paramsChanged(ElementBlock& block, int element);
  // The scene's laws of the colliders (their velocity from their center at t = 0).
  std::vector<ColliderMotion> sceneColliderMotion() const;

  Scene scene_;
  int n_ = 0;
  std::vector<ElementBlock> blocks_;
  ContributionCsr csr_;
  bool moving_pins_ = false;
  bool moving_colliders_ = false;
  bool time_dependent_fields_ = false;
  std::vector<Ramp> pin_ramps_;
  int ramped_pins_ = 0;
  Ramp user_forces_;
  std::vector<ColliderMotion> collider_motion_;  // one per collider
  int driven_colliders_ = 0;
  int forcing_version_ = 0;
  int forces_version_ = 0;
  int layout_version_ = 0;
  std::vector<std::vector<std::uint8_t>> enabled_;  // per block; empty: all enabled
};

}  // namespace stabint
