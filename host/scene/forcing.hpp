#pragma once
// The forcing of a running simulation (docs/method.md, "Per-frame input"): the scene's laws for
// pin targets, force fields and collider motion, and over them what the user changed at run time
// as linear ramps over a step. Part of the running state, not of the scene: the driver owns one
// next to its SceneData (which holds the scene and its elements), a checkpoint saves its State
// as a value, and the backends, the solver and the contact rules read it.
#include "scene/scene_batch.hpp"

#include <stabint/scene.hpp>

#include <Eigen/Core>

#include <vector>

namespace stabint {

class Forcing {
 public:
  /// A value set at t0 that moves linearly to its next value at t1 and stays there.
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
  /// Everything the run-time input changed, as one value: what a checkpoint saves and restores.
  struct State {
    std::vector<Ramp> pins;  // one per pin; inactive: the scene's law
    Ramp user_forces;
    std::vector<ColliderMotion> colliders;  // one per collider; empty: the scene's laws
  };

  /// The scene's laws, no user input. `scene` (a SceneData's, whose pins change with grabs and
  /// releases: pinsChanged) must outlive the forcing.
  explicit Forcing(const Scene& scene);

  // ---- the forcing at time t ---------------------------------------------------------------
  /// External force m_j g + sum of force fields + the user's forces at time t, `n by 3`.
  void externalForces(double t, Eigen::MatrixX3d& out) const;
  /// Target of pin i at time t: the user's ramp once one was set, else the scene's law q(t).
  Eigen::Vector3d pinTarget(int pin, double t) const;
  /// Where collider c's reference point (Collider::center) is at time t, and how fast it moves
  /// there (over the step ending at t when t ends a ramp).
  Eigen::Vector3d colliderPosition(int collider, double t) const;
  Eigen::Vector3d colliderVelocity(int collider, double t) const;
  /// The collider's geometry (host/elements/contact.hpp) at time t.
  void colliderGeometry(int collider, double t, double* geometry) const;
  bool hasMovingPins() const { return moving_pins_ || ramped_pins_ > 0; }
  /// A collider moves by its scene velocity or was driven at run time: the contact params depend
  /// on time and the collider does work.
  bool hasMovingColliders() const { return moving_colliders_ || driven_colliders_ > 0; }
  /// External forces that may change with time: a force field that varies or a user ramp.
  bool hasTimeDependentForces() const { return time_dependent_fields_ || user_forces_.active; }
  /// Per segment of `segments` (a batch's scenes; a Simulator's one scene): whether its forcing
  /// differs anywhere between t0 and t1, so that a step over [t0, t1] does work through it: a
  /// moving or ramped pin on its particles, a time-dependent force field or a user-force ramp
  /// acting on them, one of its colliders moving. False once every ramp has reached its end value
  /// and no law moves.
  std::vector<char> changesDuring(double t0, double t1, const std::vector<SceneSegment>& segments) const;

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

  /// The scene's pins were replaced (SceneData::setPins) from `before`: the ramps of the pins
  /// that keep their index and vertex stay, the others are dropped.
  void pinsChanged(const std::vector<Pin>& before);

  /// The forcing as a value, and a saved one of the same scene put back (sizes checked by the
  /// caller).
  State state() const { return State{pin_ramps_, user_forces_, collider_motion_}; }
  void setState(const State& state);

  /// Incremented by every change (ramps, pins, setState), so cached forcing is refreshed.
  int version() const { return version_; }
  /// Incremented by every change of what externalForces gives (user-force ramps, setState); the
  /// changes of pins and colliders, which move version(), leave it.
  int forcesVersion() const { return forces_version_; }

 private:
  // The scene's laws of the colliders (their velocity from their center at t = 0).
  std::vector<ColliderMotion> sceneColliderMotion() const;
  void countRampedPins();

  const Scene* scene_;
  bool moving_pins_ = false;
  bool moving_colliders_ = false;
  bool time_dependent_fields_ = false;
  std::vector<Ramp> pin_ramps_;
  int ramped_pins_ = 0;
  Ramp user_forces_;
  std::vector<ColliderMotion> collider_motion_;  // one per collider
  int driven_colliders_ = 0;
  int version_ = 0;
  int forces_version_ = 0;
};

}  // namespace stabint
