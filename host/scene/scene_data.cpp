// SceneData: validation once, then the element blocks and the gather lists both backends read
// every iteration.
#include "scene/scene_data.hpp"

#include "elements/contact.hpp"

#include <algorithm>

namespace stabint {

namespace {

// Counting sort of (vertex, contribution) pairs by vertex. Contributions are visited in
// ascending order, so each vertex's list comes out sorted without a separate sort.
ContributionCsr buildCsr(int n, const std::vector<ElementBlock>& blocks) {
  ContributionCsr csr;
  std::vector<int> target;
  for (const ElementBlock& block : blocks) target.insert(target.end(), block.vertices.begin(), block.vertices.end());
  csr.numContributions = static_cast<int>(target.size());
  csr.offsets.assign(n + 1, 0);
  for (int v : target) ++csr.offsets[v + 1];
  for (int j = 0; j < n; ++j) csr.offsets[j + 1] += csr.offsets[j];
  csr.contributions.resize(csr.numContributions);
  std::vector<int> fill(csr.offsets.begin(), csr.offsets.end() - 1);
  for (int c = 0; c < csr.numContributions; ++c) csr.contributions[fill[target[c]]++] = c;
  return csr;
}

}  // namespace

SceneData::SceneData(const Scene& scene) {
  // Validate before copying anything: a throw leaves no half-built object behind.
  validateScene(scene);
  scene_ = scene;
  n_ = scene.numParticles();
  buildBlocks();
  moving_pins_ = std::any_of(scene_.pins.begin(), scene_.pins.end(), [](const Pin& p) { return p.target.moving(); });
  time_dependent_fields_ = std::any_of(scene_.force_fields.begin(), scene_.force_fields.end(),
                                       [](const ForceField& f) { return f.timeDependent(); });
  moving_colliders_ =
      std::any_of(scene_.colliders.begin(), scene_.colliders.end(), [](const Collider& c) { return c.moving(); });
  pin_ramps_.resize(scene_.pins.size());
  collider_motion_ = sceneColliderMotion();
}

std::vector<SceneData::ColliderMotion> SceneData::sceneColliderMotion() const {
  std::vector<ColliderMotion> motion;
  for (const Collider& c : scene_.colliders)
    motion.push_back(ColliderMotion{0.0, 0.0, c.center, c.center, c.velocity, false});
  return motion;
}

Eigen::Vector3d SceneData::ColliderMotion::at(double t) const {
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

Eigen::Vector3d SceneData::ColliderMotion::velocityAt(double t) const {
  if (t1 > t0 && !(t > t1)) return (end - start) / (t1 - t0);
  return velocity;
}

bool SceneData::ColliderMotion::movesDuring(double a, double b) const {
  if (!velocity.isZero(0.0) && b > t1) return true;
  return t1 > a && t0 < b && start != end;
}

Eigen::Vector3d SceneData::colliderPosition(int collider, double t) const {
  return collider_motion_[static_cast<std::size_t>(collider)].at(t);
}

Eigen::Vector3d SceneData::colliderVelocity(int collider, double t) const {
  return collider_motion_[static_cast<std::size_t>(collider)].velocityAt(t);
}

void SceneData::colliderGeometry(int collider, double t, double* geometry) const {
  colliderGeometryAt(scene_.colliders[static_cast<std::size_t>(collider)], colliderPosition(collider, t), geometry);
}

Eigen::MatrixX3d SceneData::Ramp::at(double t) const {
  // s is exactly 0 at t0 and exactly 1 at t1 (t1 - t0 divided by itself), so a step's start and
  // end see the values the user gave, bit for bit.
  if (!(t < t1)) return end;
  if (!(t > t0)) return start;
  const double s = (t - t0) / (t1 - t0);
  return (1.0 - s) * start + s * end;
}

void SceneData::externalForces(double t, Eigen::MatrixX3d& out) const {
  out = scene_.masses * scene_.gravity.transpose();
  for (const ForceField& field : scene_.force_fields) {
    const Eigen::RowVector3d f = field.at(t).transpose();
    if (field.particles.empty()) {
      out.rowwise() += f;
    } else {
      for (int j : field.particles) out.row(j) += f;
    }
  }
  if (user_forces_.active) out += user_forces_.at(t);
}

Eigen::Vector3d SceneData::pinTarget(int pin, double t) const {
  const Ramp& ramp = pin_ramps_[pin];
  if (ramp.active) return ramp.at(t).row(0).transpose();
  return scene_.pins[pin].target.at(t);
}

void SceneData::pinTargets(double t, Eigen::MatrixX3d& out) const {
  out.resize(static_cast<Eigen::Index>(scene_.pins.size()), 3);
  for (size_t i = 0; i < scene_.pins.size(); ++i) out.row(i) = pinTarget(static_cast<int>(i), t).transpose();
}

std::vector<char> SceneData::forcingChangesDuring(double t0, double t1,
                                                  const std::vector<SceneSegment>& segments) const {
  std::vector<char> forced(segments.size(), 0);
  if (segments.empty()) return forced;
  auto segmentOf = [&](int particle) {
    const auto after = std::upper_bound(segments.begin(), segments.end(), particle,
                                        [](int j, const SceneSegment& seg) { return j < seg.first_particle; });
    return static_cast<std::size_t>(after - segments.begin()) - 1;
  };
  auto during = [&](const Ramp& r) { return r.active && r.t1 > t0 && r.t0 < t1; };
  for (std::size_t i = 0; i < scene_.pins.size(); ++i) {
    const Ramp& ramp = pin_ramps_[i];
    if (scene_.pins[i].target.moving() || (during(ramp) && ramp.start != ramp.end))
      forced[segmentOf(scene_.pins[i].vertex)] = 1;
  }
  for (const ForceField& field : scene_.force_fields) {
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

void SceneData::rampPinTarget(int pin, const Eigen::Vector3d& target, double t0, double t1) {
  Ramp& ramp = pin_ramps_[pin];
  const Eigen::Vector3d start = pinTarget(pin, t0);
  if (!ramp.active) ++ramped_pins_;
  ramp = Ramp{t0, t1, start.transpose(), target.transpose(), true};
  ++forcing_version_;
}

void SceneData::rampUserForces(const Eigen::MatrixX3d& forces, double t0, double t1) {
  const Eigen::MatrixX3d start = user_forces_.active ? user_forces_.at(t0) : Eigen::MatrixX3d::Zero(n_, 3);
  user_forces_ = Ramp{t0, t1, start, forces, true};
  ++forcing_version_;
  ++forces_version_;
}

void SceneData::rampUserForceRows(int first, const Eigen::MatrixX3d& forces, double t0, double t1) {
  if (!user_forces_.active || user_forces_.t0 != t0 || user_forces_.t1 != t1) {
    // A new ramp for every row, each going on to the value it was given (start: its value at t0).
    Eigen::MatrixX3d all = user_forces_.active ? user_forces_.end : Eigen::MatrixX3d::Zero(n_, 3);
    all.middleRows(first, forces.rows()) = forces;
    rampUserForces(all, t0, t1);
    return;
  }
  // The ramp over this [t0, t1] already holds every row: its start is each row's value at t0
  // (what rampUserForces would take again), so only these rows' end changes.
  user_forces_.end.middleRows(first, forces.rows()) = forces;
  ++forcing_version_;
  ++forces_version_;
}

void SceneData::rampColliderPosition(int collider, const Eigen::Vector3d& position, double t0, double t1) {
  ColliderMotion& m = collider_motion_[static_cast<std::size_t>(collider)];
  const Eigen::Vector3d start = m.at(t0);
  if (!m.driven) ++driven_colliders_;
  m = ColliderMotion{t0, t1, start, position, Eigen::Vector3d::Zero(), true};
  ++forcing_version_;
}

void SceneData::setColliderVelocity(int collider, const Eigen::Vector3d& velocity, double t0) {
  ColliderMotion& m = collider_motion_[static_cast<std::size_t>(collider)];
  const Eigen::Vector3d start = m.at(t0);
  if (!m.driven) ++driven_colliders_;
  m = ColliderMotion{t0, t0, start, start, velocity, true};
  ++forcing_version_;
}

void SceneData::buildBlocks() {
  for (const ElementType* type : elementTypes()) blocks_.push_back(type->build(scene_));
  enabled_.resize(blocks_.size());
  numberContributions();
}

int SceneData::blockIndex(const ElementType& type) const {
  for (std::size_t b = 0; b < blocks_.size(); ++b)
    if (blocks_[b].type == &type) return static_cast<int>(b);
  return -1;  // not reached: every type of elementTypes() has a block
}

void SceneData::applyEnabled(std::size_t block) {
  ElementBlock& b = blocks_[block];
  const std::vector<std::uint8_t>& flags = enabled_[block];
  const std::size_t p = static_cast<std::size_t>(b.type->shape().params);
  for (std::size_t e = 0; e < flags.size(); ++e)
    if (!flags[e]) b.params[p * e] = 0.0;
}

void SceneData::setElementStiffness(int block, int element, double stiffness) {
  ElementBlock& b = blocks_[static_cast<std::size_t>(block)];
  b.type->setStiffness(scene_, element, stiffness);
  const std::size_t p = static_cast<std::size_t>(b.type->shape().params);
  b.type->elementParams(scene_, element, &b.params[p * static_cast<std::size_t>(element)]);
  if (!elementEnabled(block, element)) b.params[p * static_cast<std::size_t>(element)] = 0.0;
  paramsChanged(b, element);
  ++forcing_version_;  // cached time-dependent params (pins) carry the weight too
}

void SceneData::paramsChanged(ElementBlock& block, int element) {
  // [project rule] The log is trimmed by half when it reaches this length: amortised O(1) per
  // change, and a copy that missed more changes than that refreshes the whole block.
  constexpr std::size_t kMaxLog = 512;
  ++block.params_revision;
  if (block.changed_params.size() >= kMaxLog)
    block.changed_params.erase(block.changed_params.begin(),
                               block.changed_params.begin() + std::ptrdiff_t(kMaxLog / 2));
  block.changed_params.push_back(element);
}

void SceneData::setElementEnabled(int block, int element, bool enabled) {
  ElementBlock& b = blocks_[static_cast<std::size_t>(block)];
  std::vector<std::uint8_t>& flags = enabled_[static_cast<std::size_t>(block)];
  if (flags.empty()) flags.assign(static_cast<std::size_t>(b.count), 1);
  flags[static_cast<std::size_t>(element)] = enabled ? 1 : 0;
  const std::size_t p = static_cast<std::size_t>(b.type->shape().params);
  if (enabled) {
    b.type->elementParams(scene_, element, &b.params[p * static_cast<std::size_t>(element)]);
  } else {
    b.params[p * static_cast<std::size_t>(element)] = 0.0;
  }
  paramsChanged(b, element);
  ++forcing_version_;
}

void SceneData::numberContributions() {
  int base = 0;
  for (ElementBlock& block : blocks_) {
    block.contribution_base = base;
    base += static_cast<int>(block.vertices.size());
  }
  csr_ = buildCsr(n_, blocks_);
}

void SceneData::setPins(const std::vector<Pin>& pins) {
  Scene candidate;
  candidate.positions = scene_.positions;  // sizes for the index checks
  candidate.pins = pins;
  pinElementType().validate(candidate);
  std::vector<Ramp> ramps(pins.size());
  for (std::size_t i = 0; i < pins.size() && i < scene_.pins.size(); ++i)
    if (pins[i].vertex == scene_.pins[i].vertex) ramps[i] = pin_ramps_[i];
  scene_.pins = pins;
  pin_ramps_ = std::move(ramps);
  ramped_pins_ =
      static_cast<int>(std::count_if(pin_ramps_.begin(), pin_ramps_.end(), [](const Ramp& r) { return r.active; }));
  moving_pins_ = std::any_of(scene_.pins.begin(), scene_.pins.end(), [](const Pin& p) { return p.target.moving(); });
  // Only the pin block is rebuilt (in place: backends keep pointers to the blocks); the others
  // keep their data and, pins being last in the table, their contribution numbers.
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    ElementBlock& block = blocks_[b];
    if (block.type != &pinElementType()) continue;
    const int revision = block.revision;
    block = pinElementType().build(scene_);
    block.revision = revision + 1;
    // Grabbed pins are enabled; the others keep their flags.
    if (!enabled_[b].empty()) enabled_[b].resize(pins.size(), 1);
    applyEnabled(b);
  }
  numberContributions();
  ++forcing_version_;
  ++layout_version_;
}

void SceneData::setForcingState(const ForcingState& state) {
  pin_ramps_ = state.pins;
  ramped_pins_ =
      static_cast<int>(std::count_if(pin_ramps_.begin(), pin_ramps_.end(), [](const Ramp& r) { return r.active; }));
  user_forces_ = state.user_forces;
  collider_motion_ = state.colliders.empty() ? sceneColliderMotion() : state.colliders;
  driven_colliders_ = static_cast<int>(std::count_if(collider_motion_.begin(), collider_motion_.end(),
                                                     [](const ColliderMotion& m) { return m.driven; }));
  ++forcing_version_;
  ++forces_version_;
}

}  // namespace stabint
