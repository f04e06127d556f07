#include "contact/contact_resolver.hpp"

#include "contact/collider_queries.hpp"
#include "contact/contact_rules.hpp"
#include "elements/element_type.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"

#include <stabint/errors.hpp>

#include <algorithm>

namespace stabint {
namespace {

// The log of updates since the last assembly is bounded too (a checkpoint's restore replays it).
constexpr int kMaxContactLogColumns = 4096;

// [project rule] A pair leaves within the solve once its particle has risen this share of the
// set's margin above its collider since the step's start (about 0.1 mm at the defaults): far
// above the solve's round-off, and early enough that the lift is not held back (with the rise
// alone as the rule, a 40 x 40 cloth's 10-iteration BE lift cost its hand 3.7 J at 0.1 mm and
// 7.8 J at 0.4 mm, against 56 J with the set kept).
constexpr double kReleaseRise = 0.005;

}  // namespace

ContactResolver::ContactResolver(SceneData& scene, const Forcing& forcing, GlobalSystem& system,
                                 const SimulatorOptions& options, double t, const Eigen::MatrixX3d& x,
                                 const Eigen::MatrixX3d& v)
    : scene_(scene),
      forcing_(forcing),
      system_(system),
      time_step_(options.time_step),
      tolerance_(options.contact_tolerance),
      block_(scene.blockIndex(contactElementType())) {
  meshes_ = meshColliders(scene.scene(), count());
  if (count() == 0) return;
  for (int e = 0; e < count(); ++e) scene_.setElementEnabled(block_, e, false);
  const ContactSetChange change =
      contactSetChange(scene_, forcing_, meshes_, wholeScene(scene_), t, time_step_, margin(), x, v);
  for (int e : change.entering) scene_.setElementEnabled(block_, e, true);
  writeHalfSpaces(scene_, forcing_, meshes_, wholeScene(scene_), t, time_step_, x, v);
  system_.assemble(scene_);
}

int ContactResolver::count() const { return block_ < 0 ? 0 : scene_.blocks()[static_cast<std::size_t>(block_)].count; }

// Enter a pair while x_j or x_j + h v_j is this close to its collider: the final projection's
// depth plus the fall under gravity over one step beyond the prediction.
double ContactResolver::margin() const { return tolerance_ + time_step_ * time_step_ * scene_.scene().gravity.norm(); }

// Pairs entering and leaving the set: their flags, then L and the factors by one
// GlobalSystem::apply of their diagonal terms (a leaving pair's weight is read while it is in).
// With `refactor` L is assembled and factored again whatever the change's size. Returns whether
// it was.
bool ContactResolver::changeSet(const std::vector<int>& entering, const std::vector<int>& leaving, bool refactor) {
  const std::vector<int>& particle = scene_.blocks()[static_cast<std::size_t>(block_)].vertices;
  GlobalSystem::WeightChange weights;
  for (int e : entering) {
    scene_.setElementEnabled(block_, e, true);
    weights.addDiagonal(particle[static_cast<std::size_t>(e)], scene_.elementWeight(block_, e));
  }
  for (int e : leaving) {
    weights.addDiagonal(particle[static_cast<std::size_t>(e)], -scene_.elementWeight(block_, e));
    scene_.setElementEnabled(block_, e, false);
  }
  return system_.apply(weights, scene_, refactor ? GlobalSystem::Update::Refactor : GlobalSystem::Update::Cheapest);
}

std::vector<char> ContactResolver::updateSet(double t, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v,
                                             const std::vector<ContactPart>& parts) {
  std::vector<char> potential_changed(parts.size(), 0);
  if (count() == 0) return potential_changed;
  // The parts' changes as one (ascending: parts in order, each a contiguous run of pairs).
  ContactSetChange change;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    ContactSetChange part = contactSetChange(scene_, forcing_, meshes_, parts[i], t, time_step_, margin(), x, v);
    change.entering.insert(change.entering.end(), part.entering.begin(), part.entering.end());
    change.leaving.insert(change.leaving.end(), part.leaving.begin(), part.leaving.end());
    potential_changed[i] = part.entered_inside ? 1 : 0;
  }
  if (!change.empty()) changeSetLogged(change.entering, change.leaving);
  const std::vector<char> changed = refreshHalfSpaces(t, x, v, parts);
  for (std::size_t i = 0; i < parts.size(); ++i) potential_changed[i] = potential_changed[i] || changed[i];
  return potential_changed;
}

std::vector<char> ContactResolver::releaseSeparating(double t0, const Eigen::MatrixX3d& x0, const Eigen::MatrixX3d& v0,
                                                     double t, const Eigen::MatrixX3d& x,
                                                     const Eigen::MatrixX3d& forces,
                                                     const std::vector<ContactPart>& parts) {
  std::vector<char> released(parts.size(), 0);
  if (count() == 0) return released;
  std::vector<int> leaving;
  const double rise = kReleaseRise * margin();
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::vector<int> part = separatingPairs(scene_, forcing_, parts[i], t0, x0, v0, t, x, forces, rise);
    leaving.insert(leaving.end(), part.begin(), part.end());
    released[i] = part.empty() ? 0 : 1;
  }
  if (leaving.empty()) return released;
  const ElementBlock& block = scene_.blocks()[static_cast<std::size_t>(block_)];
  const std::size_t P = static_cast<std::size_t>(block.type->shape().params);
  for (int e : leaving) {
    Released r{e, {}};
    const double* g = block.params.data() + P * std::size_t(e) + kContactGeometry;
    std::copy(g, g + kColliderGeometry, r.geometry.begin());
    released_.push_back(r);
  }
  changeSetLogged({}, leaving);
  return released;
}

template <class Returning>
std::vector<char> ContactResolver::returnReleasedIf(const std::vector<ContactPart>& parts, Returning returning) {
  std::vector<char> returned(parts.size(), 0);
  if (released_.empty()) return returned;
  const Scene& scene = scene_.scene();
  std::vector<Released> entering, kept;
  for (const Released& r : released_) {
    bool in = false;
    for (std::size_t i = 0; i < parts.size() && !in; ++i) {
      const ContactPart& part = parts[i];
      const int first = firstContactElement(scene, part.colliders.first);
      if (r.pair < first || r.pair >= firstContactElement(scene, part.colliders.end())) continue;
      if (!returning(part, r)) continue;
      in = true;
      returned[i] = 1;
    }
    (in ? entering : kept).push_back(r);
  }
  released_ = kept;
  if (entering.empty()) return returned;
  std::sort(entering.begin(), entering.end(), [](const Released& a, const Released& b) { return a.pair < b.pair; });
  std::vector<int> pairs;
  for (const Released& r : entering) pairs.push_back(r.pair);
  changeSetLogged(pairs, {});
  for (const Released& r : entering)
    scene_.setElementParams(block_, r.pair, kContactGeometry, r.geometry.data(), kColliderGeometry);
  return returned;
}

std::vector<char> ContactResolver::returnPenetrating(double t, const Eigen::MatrixX3d& x,
                                                     const std::vector<ContactPart>& parts) {
  const Scene& scene = scene_.scene();
  return returnReleasedIf(parts, [&](const ContactPart& part, const Released& r) {
    // The pair's collider: the one whose run of pairs holds it.
    int c = part.colliders.first;
    while (firstContactElement(scene, c + 1) <= r.pair) ++c;
    const int j = r.pair - firstContactElement(scene, c) + colliderParticles(scene, c).first;
    double g[kColliderGeometry];
    std::copy(r.geometry.begin(), r.geometry.end(), g);
    translateGeometry(forcing_.colliderPosition(c, t) - scene.colliders[std::size_t(c)].center, g);
    const Eigen::Index row = j - part.first_row;
    const double at[3] = {x(row, 0), x(row, 1), x(row, 2)};
    return signedDistance(g, at) < 0.0;
  });
}

void ContactResolver::returnReleased(const std::vector<ContactPart>& parts) {
  returnReleasedIf(parts, [](const ContactPart&, const Released&) { return true; });
}

void ContactResolver::changeSetLogged(const std::vector<int>& entering, const std::vector<int>& leaving) {
  const int columns = static_cast<int>(entering.size() + leaving.size());
  if (changeSet(entering, leaving, log_columns_ + columns > kMaxContactLogColumns)) {
    log_.clear();
    log_columns_ = 0;
    return;
  }
  for (int e : entering) log_.push_back(e + 1);
  for (int e : leaving) log_.push_back(-(e + 1));
  log_.push_back(0);
  log_columns_ += columns;
}

void ContactResolver::setSupports(const std::vector<Supports>& supports) {
  const Scene& scene = scene_.scene();
  std::vector<int> entering, leaving;
  std::vector<std::pair<int, const SupportPlane*>> planes;  // (pair, its plane)
  for (const Supports& set : supports) {
    const IndexRange particles = colliderParticles(scene, set.collider);
    const int first = firstContactElement(scene, set.collider);
    std::vector<const SupportPlane*> of(static_cast<std::size_t>(particles.count), nullptr);
    for (const SupportPlane& plane : set.planes) of[std::size_t(plane.particle - particles.first)] = &plane;
    for (int k = 0; k < particles.count; ++k) {
      const int e = first + k;
      const bool in = scene_.elementEnabled(block_, e);
      if (of[std::size_t(k)] && !in) entering.push_back(e);
      if (!of[std::size_t(k)] && in) leaving.push_back(e);
      if (of[std::size_t(k)]) planes.emplace_back(e, of[std::size_t(k)]);
    }
  }
  if (!entering.empty() || !leaving.empty()) changeSetLogged(entering, leaving);
  for (const auto& [e, plane] : planes) {
    const Eigen::Vector3d& point = plane->point;
    double geometry[kColliderGeometry] = {};
    geometry[kGeometryShape] = static_cast<double>(static_cast<int>(ColliderShape::Plane));
    for (int c = 0; c < 3; ++c) {
      geometry[kGeometryCenter + c] = point[c];
      geometry[kGeometryA + c] = plane->normal[c];
    }
    scene_.setElementParams(block_, e, kContactGeometry, geometry, kColliderGeometry);
  }
}

double ContactResolver::supportHeight(int e, const double* x) const {
  const ElementBlock& block = scene_.blocks()[static_cast<std::size_t>(block_)];
  const double* g = block.params.data() + std::size_t(block.type->shape().params) * std::size_t(e) + kContactGeometry;
  double height = 0.0;
  for (int c = 0; c < 3; ++c) height += (x[c] - g[kGeometryCenter + c]) * g[kGeometryA + c];
  return height;
}

bool ContactResolver::relaxSupports(int collider, const Eigen::MatrixX3d& x) {
  const Scene& scene = scene_.scene();
  const IndexRange particles = colliderParticles(scene, collider);
  const int first = firstContactElement(scene, collider);
  const ElementBlock& block = scene_.blocks()[static_cast<std::size_t>(block_)];
  const std::size_t P = static_cast<std::size_t>(block.type->shape().params);
  bool moved = false;
  for (int k = 0; k < particles.count; ++k) {
    const int e = first + k;
    if (!scene_.elementEnabled(block_, e)) continue;
    const int j = particles.first + k;
    const Eigen::Vector3d at = x.row(j).transpose();
    const double depth = supportHeight(e, at.data());
    if (!(depth < 0.0)) continue;
    // Clearly below x, where a float device's rounding also finds x outside (energy exactly 0, as
    // without the plane).
    const double below = depth - 1e-6 * (1.0 + at.cwiseAbs().maxCoeff());
    const double* g = block.params.data() + P * std::size_t(e) + kContactGeometry;
    double geometry[kColliderGeometry];
    std::copy(g, g + kColliderGeometry, geometry);
    for (int c = 0; c < 3; ++c) geometry[kGeometryCenter + c] += below * geometry[kGeometryA + c];
    scene_.setElementParams(block_, e, kContactGeometry, geometry, kColliderGeometry);
    moved = true;
  }
  return moved;
}

std::vector<double> ContactResolver::supportImpulses(int collider, const std::vector<SupportPlane>& supports,
                                                     const Eigen::MatrixX3d& x, int first_row) const {
  const int first = firstContactElement(scene_.scene(), collider) - colliderParticles(scene_.scene(), collider).first;
  std::vector<double> impulses;
  for (const SupportPlane& s : supports) {
    const int e = first + first_row + s.particle;
    const Eigen::Vector3d at = x.row(s.particle).transpose();
    impulses.push_back(time_step_ * scene_.elementWeight(block_, e) * std::max(0.0, -supportHeight(e, at.data())));
  }
  return impulses;
}

std::vector<char> ContactResolver::refreshHalfSpaces(double t, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v,
                                                     const std::vector<ContactPart>& parts) {
  std::vector<char> changed(parts.size(), 0);
  if (count() == 0) return changed;
  for (std::size_t i = 0; i < parts.size(); ++i)
    changed[i] = writeHalfSpaces(scene_, forcing_, meshes_, parts[i], t, time_step_, x, v) ? 1 : 0;
  return changed;
}

ContactResolver::Resolved ContactResolver::applyFrictionAndProjection(
    const ContactPart& part, double t1, const Eigen::Ref<const Eigen::MatrixX3d, 0, Eigen::OuterStride<>>& x0,
    Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, double& target, StepReport& report) const {
  Resolved resolved;
  if (part.colliders.count == 0) return resolved;
  resolved.velocities_changed =
      applyFriction(scene_, forcing_, meshes_, part, t1, time_step_, x, v, report.friction) > 0;
  target -= report.friction;
  std::vector<double> drops;
  const StepStart start{t1 - time_step_, x0};
  resolved.positions_moved =
      projectOutOfColliders(scene_, forcing_, meshes_, part, t1, tolerance_, x, &drops, &start) > 0;
  // The share of the projection's removal the colliders' restitution keeps, weighed by the
  // contact energy each collider's moves took.
  double total = 0.0, kept = 0.0;
  for (int c = 0; c < part.colliders.count; ++c) {
    const double e = scene_.scene().colliders[std::size_t(part.colliders.first + c)].restitution;
    total += drops[std::size_t(c)];
    kept += drops[std::size_t(c)] * e * e;
  }
  resolved.kept = total > 0.0 ? kept / total : 1.0;
  resolved.removed = total;
  return resolved;
}

bool ContactResolver::projectOut(const ContactPart& part, double t1,
                                 const Eigen::Ref<const Eigen::MatrixX3d, 0, Eigen::OuterStride<>>& x0,
                                 Eigen::MatrixX3d& x) const {
  if (part.colliders.count == 0) return false;
  const StepStart start{t1 - time_step_, x0};
  return projectOutOfColliders(scene_, forcing_, meshes_, part, t1, tolerance_, x, nullptr, &start) > 0;
}

Eigen::MatrixX3d ContactResolver::heldNormals(const ContactPart& part, double t, const Eigen::MatrixX3d& x,
                                              double margin) const {
  Eigen::MatrixX3d normals = Eigen::MatrixX3d::Zero(x.rows(), 3);
  if (part.colliders.count == 0) return normals;
  const Scene& scene = scene_.scene();
  const ElementBlock& block = scene_.blocks()[static_cast<std::size_t>(block_)];
  // The least height above a collider found for each particle (of several, the nearest holds it).
  Eigen::VectorXd least = Eigen::VectorXd::Constant(x.rows(), margin);
  // Pairs in the contact set: their half-space, where x is within `margin` of its plane.
  int e = firstContactElement(scene, part.colliders.first);
  for (int c = part.colliders.first; c < part.colliders.end(); ++c) {
    const Eigen::Vector3d shift = forcing_.colliderPosition(c, t) - scene.colliders[std::size_t(c)].center;
    const IndexRange particles = colliderParticles(scene, c);
    for (int j = particles.first; j < particles.end(); ++j, ++e) {
      if (!scene_.elementEnabled(block_, e)) continue;
      const double* g =
          block.params.data() + std::size_t(block.type->shape().params) * std::size_t(e) + kContactGeometry;
      const Eigen::Vector3d point =
          Eigen::Vector3d(g[kGeometryCenter], g[kGeometryCenter + 1], g[kGeometryCenter + 2]) + shift;
      const Eigen::Vector3d normal(g[kGeometryA], g[kGeometryA + 1], g[kGeometryA + 2]);
      const Eigen::Index r = j - part.first_row;
      const double height = normal.dot(x.row(r).transpose() - point);
      if (!(height < least[r])) continue;
      least[r] = height;
      normals.row(r) = normal.transpose();
    }
  }
  // Particles inside a collider whose pair is out of the set (the solve pushed them in): the
  // direction out of it.
  forEachContact(scene_, forcing_, meshes_, part, t, x,
                 [&](int, int, Eigen::Index r, const Eigen::Vector3d& p, double depth, int pair) {
                   if (scene_.elementEnabled(block_, pair) || !(-depth < least[r])) return;
                   least[r] = -depth;
                   normals.row(r) = ((p - x.row(r).transpose()) / depth).transpose();
                 });
  return normals;
}

void ContactResolver::bookProjection(const PotentialEnergy& projected, double kept, PotentialEnergy& p, double& target,
                                     StepReport& report) {
  ++report.energy_evaluations;
  // [project rule] Only the energy the projection removes is booked, and of that only the share
  // the colliders' restitution does not keep (1 - e^2: an impact that keeps e of its normal
  // speed keeps e^2 of its energy); the kept share stays in H*, and the blend gives it back as
  // the bounce. Energy the projection adds, by lifting particles against gravity or stretching
  // their elements, is the solver's residual, not booked (booked, it let the blend pump a cloth
  // falling onto a sphere to 3,000 J in 15 steps): the blend takes it out of the step's motion
  // where it lifts H above H* (BlendStep::takeOutProjectionExcess).
  const double removed = std::min(0.0, projected.total() - p.total()) * (1.0 - kept);
  report.contact_projection += removed;
  target += removed;
  p = projected;
}

std::vector<std::uint8_t> ContactResolver::baseFlags(const std::vector<std::vector<std::uint8_t>>& enabled,
                                                     const std::vector<std::int32_t>& log) const {
  return baseFlags(count() == 0 ? std::vector<std::uint8_t>() : enabled[static_cast<std::size_t>(block_)], log);
}

std::vector<std::uint8_t> ContactResolver::baseFlags(std::vector<std::uint8_t> flags,
                                                     const std::vector<std::int32_t>& log) {
  const auto corrupt = [] {
    throw InvalidInputError("checkpoint: its contact set changes do not fit its contact set");
  };
  if (flags.empty()) {
    if (!log.empty()) corrupt();
    return {};
  }
  if (!log.empty() && log.back() != 0) corrupt();
  for (std::size_t i = log.size(); i-- > 0;) {
    const std::int64_t entry = log[i];
    if (entry == 0) continue;
    const std::int64_t e = (entry > 0 ? entry : -entry) - 1;
    if (e >= static_cast<std::int64_t>(flags.size())) corrupt();
    std::uint8_t& flag = flags[static_cast<std::size_t>(e)];
    if ((flag != 0) != (entry > 0)) corrupt();  // it entered: it is in; it left: it is out
    flag = entry > 0 ? 0 : 1;
  }
  return flags;
}

// The same rank updates in the same order as the run that wrote the log give the same factors.
void ContactResolver::restore(const std::vector<std::int32_t>& log) {
  system_.assemble(scene_);
  system_.refactorAll();
  std::vector<int> entering, leaving;
  for (std::int32_t entry : log) {
    if (entry > 0) entering.push_back(entry - 1);
    if (entry < 0) leaving.push_back(-entry - 1);
    if (entry != 0) continue;
    if (!entering.empty() || !leaving.empty()) changeSet(entering, leaving, false);
    entering.clear();
    leaving.clear();
  }
  log_ = log;
  log_columns_ = static_cast<int>(std::count_if(log.begin(), log.end(), [](std::int32_t entry) { return entry != 0; }));
}

}  // namespace stabint
