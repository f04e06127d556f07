#include "integrator/frame_input.hpp"

#include "validation.hpp"

#include <stabint/errors.hpp>

#include <cmath>
#include <string>

namespace stabint {

FrameInput::FrameInput(SceneData& scene, double time_step, double limit)
    : scene_(scene), time_step_(time_step), limit_(limit) {}

void FrameInput::checkRows(const Eigen::MatrixX3d& m, const char* field) const {
  validation::checkInputRows(m, scene_.numParticles(), field, limit_);
}

void FrameInput::checkPin(int pin) const {
  const int pins = static_cast<int>(scene_.scene().pins.size());
  if (pin < 0 || pin >= pins)
    throw InvalidInputError("pin " + std::to_string(pin) + " out of range (the scene has " + std::to_string(pins) +
                            " pins)");
}

void FrameInput::checkCollider(int collider) const {
  const int colliders = static_cast<int>(scene_.scene().colliders.size());
  if (collider < 0 || collider >= colliders)
    throw InvalidInputError("collider " + std::to_string(collider) + " out of range (the scene has " +
                            std::to_string(colliders) + " colliders)");
}

// The bound of the scene's coordinates and speeds (validateScene): beyond it the contact
// energies overflow.
void FrameInput::checkColliderVector(int collider, const Eigen::Vector3d& value, const char* what) const {
  checkCollider(collider);
  if (!value.allFinite() || !(value.cwiseAbs().maxCoeff() <= validation::kMaxMagnitude))
    throw InvalidInputError("collider " + std::to_string(collider) + ": " + what +
                            " is not finite or exceeds 1e150 in magnitude");
}

void FrameInput::setPinTarget(int pin, const Eigen::Vector3d& q, double t) {
  checkPin(pin);
  validation::checkInputVector(q, "pin " + std::to_string(pin) + ": target", limit_);
  scene_.rampPinTarget(pin, q, t, t + time_step_);
}

void FrameInput::setColliderPosition(int collider, const Eigen::Vector3d& position, double t) {
  checkColliderVector(collider, position, "position");
  scene_.rampColliderPosition(collider, position, t, t + time_step_);
}

void FrameInput::setColliderVelocity(int collider, const Eigen::Vector3d& velocity, double t) {
  checkColliderVector(collider, velocity, "velocity");
  scene_.setColliderVelocity(collider, velocity, t);
}

void FrameInput::setExternalForces(const Eigen::MatrixX3d& forces, double t) {
  checkRows(forces, "external forces");
  scene_.rampUserForces(forces, t, t + time_step_);
}

std::vector<Pin> FrameInput::pinsAfterGrab(int vertex, double stiffness, const Eigen::MatrixX3d& x) const {
  if (vertex < 0 || vertex >= scene_.numParticles())
    throw InvalidInputError("grab: vertex " + std::to_string(vertex) + " out of range (the scene has " +
                            std::to_string(scene_.numParticles()) + " particles)");
  if (!std::isfinite(stiffness) || !(stiffness > 0.0) || !(stiffness <= validation::kMaxMagnitude))
    throw InvalidInputError("grab: stiffness " + validation::cat(stiffness) + " must be finite, > 0 and at most " +
                            validation::cat(validation::kMaxMagnitude));
  std::vector<Pin> pins = scene_.scene().pins;
  Pin handle;
  handle.vertex = vertex;
  handle.stiffness = stiffness;
  handle.target.position = x.row(vertex).transpose();
  pins.push_back(handle);
  return pins;
}

std::vector<Pin> FrameInput::pinsAfterRelease(int pin, double t) const {
  checkPin(pin);
  std::vector<Pin> pins = scene_.scene().pins;
  if (pins[pin].stiffness == 0.0)
    throw InvalidInputError("release: pin " + std::to_string(pin) + " is already released (stiffness 0)");
  pins[pin].stiffness = 0.0;
  pins[pin].target = PinTarget{};  // a released pin does no work
  pins[pin].target.position = scene_.pinTarget(pin, t);
  return pins;
}

}  // namespace stabint
