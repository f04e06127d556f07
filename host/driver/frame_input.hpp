#pragma once
// Per-frame input (docs/method.md, "Per-frame input"): the user's pin targets, external forces,
// collider motion, grabs and releases, each checked against the scene (or a batch's scene: the
// InputScope) and the backend's input bound before anything changes. Targets, forces and collider
// positions are ramped over the coming step; the driver books what changes H at once (grab,
// release) as an event.
#include "driver/input_scope.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"

#include <Eigen/Core>

#include <vector>

namespace stabint {

class FrameInput {
 public:
  /// `limit`: the bound of input magnitudes on the backend (inputLimit()). Indices and row counts
  /// are the scope's (the whole scene by default).
  FrameInput(const SceneData& scene, Forcing& forcing, double time_step, double limit, InputScope scope = {});

  /// InvalidInputError, naming `field`, unless `m` has a finite row within the bound per particle.
  void checkRows(const Eigen::MatrixX3d& m, const char* field) const;
  /// InvalidInputError for an index out of the scope's pins or colliders.
  void checkPin(int pin) const;
  void checkCollider(int collider) const;

  /// Input at time t for the step [t, t + h]: pin target q, collider position and external
  /// forces reached at t + h along a ramp, collider velocity from t on. A batch scene's forces
  /// replace its rows only: the other scenes' go on to the values they were given.
  void setPinTarget(int pin, const Eigen::Vector3d& q, double t);
  void setColliderPosition(int collider, const Eigen::Vector3d& position, double t);
  void setColliderVelocity(int collider, const Eigen::Vector3d& velocity, double t);
  void setExternalForces(const Eigen::MatrixX3d& forces, double t);

  /// The current values at time t (checked indices).
  Eigen::Vector3d pinTarget(int pin, double t) const;
  Eigen::Vector3d colliderPosition(int collider, double t) const;
  Eigen::Vector3d colliderVelocity(int collider, double t) const;

  /// The pin set after grabbing `vertex` (a new pin at its position in `x`, rows of the whole
  /// scene, after the scope's last pin: the scene's last) or releasing `pin` at time t
  /// (stiffness 0, its target frozen where it is at t).
  std::vector<Pin> pinsAfterGrab(int vertex, double stiffness, const Eigen::MatrixX3d& x) const;
  std::vector<Pin> pinsAfterRelease(int pin, double t) const;

 private:
  void checkColliderVector(int collider, const Eigen::Vector3d& value, const char* what) const;

  const SceneData& scene_;
  Forcing& forcing_;
  double time_step_, limit_;
  InputScope scope_;
};

}  // namespace stabint
