// Forcing: the scene's laws and the user's ramps over them, evaluated at any time.
#include "scene/forcing.hpp"

#include "elements/contact.hpp"

#include <algorithm>

namespace stabint {

Forcing::Forcing(const Scene& scene) : scene_(&scene) {
  moving_pins_ = std::any_of(scene.pins.begin(), scene.pins.end(), [](const Pin& p) { return p.target.moving(); });
  time_dependent_fields_ = std::any_of(scene.force_fields.begin(), scene.force_fields.end(),
                                       [](const ForceField& f) { return f.timeDependent(); });
  moving_colliders_ =
      std::any_of(scene.colliders.begin(), scene.colliders.end(), [](const Collider& c) { return c.moving(); });
  pin_ramps_.resize(scene.pins.size());
  collider_motion_ = sceneColliderMotion();
}

std::vector<Forcing::ColliderMotion> Forcing::sceneColliderMotion() const {
  std::vector<ColliderMotion> motion;
  for (const Collider& c : scene_->colliders)
    motion.push_back(ColliderMotion{0.0, 0.0, c.center, c.center, c.velocity, false});
  return motion;
}

Eigen::Vector3d Forcing::ColliderMotion::at(double t) const {
  if (t1 > t0) {
    if (!(t > t0)) return start;
    if (t < t1) {
      const double s = (t - t0) / (t1 - t0);
      return (1.0 - s) * start + s * end;
    }
  }
  // The scene's law center + t velocity is end + (t - 0) velocity: the same operations.
  if (velocity.isZero(0.0)) return end;
  return end + (t - t1) * velocity;
}

Eigen::Vector3d Forcing::ColliderMotion::velocityAt(double t) const {
  if (t1 > t0 && !(t > t1)) return (end - start) / (t1 - t0);
  return velocity;
}

bool Forcing::ColliderMotion::movesDuring(double a, double b) const {
  if (!velocity.isZero(0.0) && b > t1) return true;
  return t1 > a && t0 < b && start != end;
}

Eigen::Vector3d Forcing::colliderPosition(int collider, double t) const {
  return collider_motion_[static_cast<std::size_t>(collider)].at(t);
}

Eigen::Vector3d Forcing::colliderVelocity(int collider, double t) const {
  return collider_motion_[static_cast<std::size_t>(collider)].velocityAt(t);
}

void Forcing::colliderGeometry(int collider, double t, double* geometry) const {
  colliderGeometryAt(scene_->colliders[static_cast<std::size_t>(collider)], colliderPosition(collider, t), geometry);
}

Eigen::MatrixX3d Forcing::Ramp::at(double t) const {
  // s is exactly 0 at t0 and exactly 1 at t1 (t1 - t0 divided by itself), so a step's start and
  // end see the values the user gave, bit for bit.
  if (!(t < t1)) return end;
  if (!(t > t0)) return start;
  const double s = (t - t0) / (t1 - t0);
  return (1.0 - s) * start + s * end;
}

void Forcing::externalForces(double t, Eigen::MatrixX3d& out) const {
  out = scene_->masses * scene_->gravity.transpose();
  for (const ForceField& field : scene_->force_fields) {
    const Eigen::RowVector3d f = field.at(t).transpose();
    if (field.particles.empty()) {
      out.rowwise() += f;
    } else {
      for (int j : field.particles) out.row(j) += f;
    }
  }
  if (user_forces_.active) out += user_forces_.at(t);
}

Eigen::Vector3d Forcing::pinTarget(int pin, double t) const {
  const Ramp& ramp = pin_ramps_[static_cast<std::size_t>(pin)];
  if (ramp.active) return ramp.at(t).row(0).transpose();
  return scene_->pins[static_cast<std::size_t>(pin)].target.at(t);
}

std::vector<char> Forcing::changesDuring(double t0, double t1, const std::vector<SceneSegment>& segments) const {
  std::vector<char> forced(segments.size(), 0);
  if (segments.empty()) return forced;
  auto segmentOf = [&](int particle) {
    const auto after = std::upper_bound(segments.begin(), segments.end(), particle,
                                        [](int j, const SceneSegment& seg) { return j < seg.first_particle; });
    return static_cast<std::size_t>(after - segments.begin()) - 1;
  };
  auto during = [&](const Ramp& r) { return r.active && r.t1 > t0 && r.t0 < t1; };
  for (std::size_t i = 0; i < scene_->pins.size(); ++i) {
    const Ramp& ramp = pin_ramps_[i];
    if (scene_->pins[i].target.moving() || (during(ramp) && ramp.start != ramp.end))
      forced[segmentOf(scene_->pins[i].vertex)] = 1;
  }
  for (const ForceField& field : scene_->force_fields) {
    if (!field.timeDependent()) continue;
    if (field.particles.empty()) std::fill(forced.begin(), forced.end(), 1);
    for (int j : field.particles) forced[segmentOf(j)] = 1;
  }
  for (std::size_t s = 0; s < segments.size(); ++s) {
    const SceneSegment& seg = segments[s];
    if (during(user_forces_) && user_forces_.start.middleRows(seg.first_particle, seg.num_particles) !=
                                    user_forces_.end.middleRows(seg.first_particle, seg.num_particles))
      forced[s] = 1;
    for (int c = seg.first_collider; c < seg.first_collider + seg.num_colliders; ++c)
      if (collider_motion_[static_cast<std::size_t>(c)].movesDuring(t0, t1)) forced[s] = 1;
  }
  return forced;
}

void Forcing::rampPinTarget(int pin, const Eigen::Vector3d& target, double t0, double t1) {
  Ramp& ramp = pin_ramps_[static_cast<std::size_t>(pin)];
  const Eigen::Vector3d start = pinTarget(pin, t0);
  if (!ramp.active) ++ramped_pins_;
  ramp = Ramp{t0, t1, start.transpose(), target.transpose(), true};
  ++version_;
}

void Forcing::rampUserForces(const Eigen::MatrixX3d& forces, double t0, double t1) {
  const Eigen::MatrixX3d start =
      user_forces_.active ? user_forces_.at(t0) : Eigen::MatrixX3d::Zero(scene_->numParticles(), 3);
  user_forces_ = Ramp{t0, t1, start, forces, true};
  ++version_;
  ++forces_version_;
}

void Forcing::rampUserForceRows(int first, const Eigen::MatrixX3d& forces, double t0, double t1) {
  if (!user_forces_.active || user_forces_.t0 != t0 || user_forces_.t1 != t1) {
    // A new ramp for every row, each going on to the value it was given (start: its value at t0).
    Eigen::MatrixX3d all = user_forces_.active ? user_forces_.end : Eigen::MatrixX3d::Zero(scene_->numParticles(), 3);
    all.middleRows(first, forces.rows()) = forces;
    rampUserForces(all, t0, t1);
    return;
  }
  // The ramp over this [t0, t1] already holds every row: its start is each row's value at t0
  // (what rampUserForces would take again), so only these rows' end changes.
  user_forces_.end.middleRows(first, forces.rows()) = forces;
  ++version_;
  ++forces_version_;
}

void Forcing::rampColliderPosition(int collider, const Eigen::Vector3d& position, double t0, double t1) {
  ColliderMotion& m = collider_motion_[static_cast<std::size_t>(collider)];
  const Eigen::Vector3d start = m.at(t0);
  if (!m.driven) ++driven_colliders_;
  m = ColliderMotion{t0, t1, start, position, Eigen::Vector3d::Zero(), true};
  ++version_;
}

void Forcing::setColliderVelocity(int collider, const Eigen::Vector3d& velocity, double t0) {
  ColliderMotion& m = collider_motion_[static_cast<std::size_t>(collider)];
  const Eigen::Vector3d start = m.at(t0);
  if (!m.driven) ++driven_colliders_;
  m = ColliderMotion{t0, t0, start, start, velocity, true};
  ++version_;
}

void Forcing::countRampedPins() {
  ramped_pins_ =
      static_cast<int>(std::count_if(pin_ramps_.begin(), pin_ramps_.end(), [](const Ramp& r) { return r.active; }));
}

void Forcing::pinsChanged(const std::vector<Pin>& before) {
  const std::vector<Pin>& pins = scene_->pins;
  std::vector<Ramp> ramps(pins.size());
  for (std::size_t i = 0; i < pins.size() && i < before.size(); ++i)
    if (pins[i].vertex == before[i].vertex) ramps[i] = pin_ramps_[i];
  pin_ramps_ = std::move(ramps);
  countRampedPins();
  moving_pins_ = std::any_of(pins.begin(), pins.end(), [](const Pin& p) { return p.target.moving(); });
  ++version_;
}

void Forcing::setState(const State& state) {
  pin_ramps_ = state.pins;
  countRampedPins();
  user_forces_ = state.user_forces;
  collider_motion_ = state.colliders.empty() ? sceneColliderMotion() : state.colliders;
  driven_colliders_ = static_cast<int>(std::count_if(collider_motion_.begin(), collider_motion_.end(),
                                                     [](const ColliderMotion& m) { return m.driven; }));
  ++version_;
  ++forces_version_;
}

}  // namespace stabint
