#include "driver/frame_input.hpp"

#include "common/validation.hpp"

#include <stabint/errors.hpp>

#include <cmath>
#include <string>
#include <utility>

namespace stabint {

FrameInput::FrameInput(const SceneData& scene, Forcing& forcing, double time_step, double limit, InputScope scope)
    : scene_(scene), forcing_(forcing), time_step_(time_step), limit_(limit), scope_(std::move(scope)) {}

void FrameInput::checkRows(const Eigen::MatrixX3d& m, const char* field) const {
  validation::checkInputRows(m, scope_.particles(scene_).count, scope_.where() + field, limit_);
}

void FrameInput::checkPin(int pin) const {
  const int pins = scope_.pins(scene_).count;
  if (pin < 0 || pin >= pins)
    throw InvalidInputError(scope_.where() + "pin " + std::to_string(pin) + " out of range (the scene has " +
                            std::to_string(pins) + " pins)");
}

void FrameInput::checkCollider(int collider) const {
  const int colliders = scope_.colliders(scene_).count;
  if (collider < 0 || collider >= colliders)
    throw InvalidInputError(scope_.where() + "collider " + std::to_string(collider) + " out of range (the scene has " +
                            std::to_string(colliders) + " colliders)");
}

// The bound of per-frame input on the backend (the scene's 1e150, a float device's 1e15): beyond
// it the contact energies overflow and every later step is refused.
void FrameInput::checkColliderVector(int collider, const Eigen::Vector3d& value, const char* what) const {
  checkCollider(collider);
  validation::checkInputVector(value, scope_.where() + "collider " + std::to_string(collider) + ": " + what, limit_);
}

void FrameInput::setPinTarget(int pin, const Eigen::Vector3d& q, double t) {
  checkPin(pin);
  validation::checkInputVector(q, scope_.where() + "pin " + std::to_string(pin) + ": target", limit_);
  forcing_.rampPinTarget(scope_.pins(scene_).first + pin, q, t, t + time_step_);
}

void FrameInput::setColliderPosition(int collider, const Eigen::Vector3d& position, double t) {
  checkColliderVector(collider, position, "position");
  forcing_.rampColliderPosition(scope_.colliders(scene_).first + collider, position, t, t + time_step_);
}

void FrameInput::setColliderVelocity(int collider, const Eigen::Vector3d& velocity, double t) {
  checkColliderVector(collider, velocity, "velocity");
  forcing_.setColliderVelocity(scope_.colliders(scene_).first + collider, velocity, t);
}

void FrameInput::setExternalForces(const Eigen::MatrixX3d& forces, double t) {
  checkRows(forces, "external forces");
  const InputRange rows = scope_.particles(scene_);
  if (rows.count == scene_.numParticles()) {
    forcing_.rampUserForces(forces, t, t + time_step_);
    return;
  }
  // One ramp holds every particle's forces: the other rows go on to the values they were given
  // (a scene set earlier in this frame keeps its ramp over the same step).
  forcing_.rampUserForceRows(rows.first, forces, t, t + time_step_);
}

Eigen::Vector3d FrameInput::pinTarget(int pin, double t) const {
  checkPin(pin);
  return forcing_.pinTarget(scope_.pins(scene_).first + pin, t);
}

Eigen::Vector3d FrameInput::colliderPosition(int collider, double t) const {
  checkCollider(collider);
  return forcing_.colliderPosition(scope_.colliders(scene_).first + collider, t);
}

Eigen::Vector3d FrameInput::colliderVelocity(int collider, double t) const {
  checkCollider(collider);
  return forcing_.colliderVelocity(scope_.colliders(scene_).first + collider, t);
}

std::vector<Pin> FrameInput::pinsAfterGrab(int vertex, double stiffness, const Eigen::MatrixX3d& x) const {
  const InputRange particles = scope_.particles(scene_);
  if (vertex < 0 || vertex >= particles.count)
    throw InvalidInputError(scope_.where("grab") + "vertex " + std::to_string(vertex) +
                            " out of range (the scene has " + std::to_string(particles.count) + " particles)");
  if (!std::isfinite(stiffness) || !(stiffness > 0.0) || !(stiffness <= validation::kMaxMagnitude))
    throw InvalidInputError(scope_.where("grab") + "stiffness " + validation::cat(stiffness) +
                            " must be finite, > 0 and at most " + validation::cat(validation::kMaxMagnitude));
  std::vector<Pin> pins = scene_.scene().pins;
  Pin handle;
  handle.vertex = particles.first + vertex;
  handle.stiffness = stiffness;
  handle.target.position = x.row(handle.vertex).transpose();
  const InputRange own = scope_.pins(scene_);
  pins.insert(pins.begin() + (own.first + own.count), handle);
  return pins;
}

std::vector<Pin> FrameInput::pinsAfterRelease(int pin, double t) const {
  checkPin(pin);
  const int i = scope_.pins(scene_).first + pin;
  std::vector<Pin> pins = scene_.scene().pins;
  if (pins[i].stiffness == 0.0)
    throw InvalidInputError(scope_.where("release") + "pin " + std::to_string(pin) +
                            " is already released (stiffness 0)");
  pins[i].stiffness = 0.0;
  pins[i].target = PinTarget{};  // a released pin does no work
  pins[i].target.position = forcing_.pinTarget(i, t);
  return pins;
}

}  // namespace stabint
