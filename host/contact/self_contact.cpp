// SelfContact's steps (docs/method.md, "Self-contact"): the approach stopped before the solve, the
// supports within it and the pushes after it, each pair answered through ImpulseResponse.
#include "contact/self_contact.hpp"

#include "common/disjoint_sets.hpp"
#include "contact/impulse_response.hpp"
#include "scene/connected_bodies.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <utility>

namespace stabint {
namespace {

using Vec3 = Eigen::Vector3d;

}  // namespace

SelfContact::SelfContact(const Scene& scene, double thickness, double friction)
    : surface_(ContactSurface::of(scene)),
      thickness_(thickness),
      friction_(friction),
      solid_of_(static_cast<std::size_t>(scene.numParticles()), -1),
      solids_(tetBodies(scene)) {
  for (std::size_t b = 0; b < solids_.size(); ++b)
    for (int i : solids_[b]) solid_of_[std::size_t(i)] = static_cast<int>(b);
}

namespace {

double kinetic(const Eigen::MatrixX3d& v, const Eigen::VectorXd& masses) {
  return 0.5 * (v.rowwise().squaredNorm().transpose().array() * masses.transpose().array()).sum();
}

// [project rule] The approach stop: a side of a pair that a collider holds takes no share of the
// impulse where it would be pushed into the collider and the other side is heavy, moving at most a
// tenth as far under the impulse, as for a support (a tet body dropped onto a cloth lying on the
// ground, shared by mass, pushed the cloth into the ground and went on through it: up to 875
// bands above H*). Against a side about as light as itself it shares by mass, the collider then
// stopping its share within the solve (a cloth landing on a cloth on the ground: holding the lower
// one stopped the upper alone, and the blend scaled the landing's motion up 3.7 times).
struct Share {
  double compliance;
  bool held;
};
Share approachShare(const ImpulseResponse& response, const ContactEvent& e) {
  const double all = response.compliance(e, e.normal);
  const double other = response.compliance(e, e.normal, {true});
  if (other > 0.0 && other <= 0.1 * (all - other)) return {other, true};
  return {all, false};
}

// [project rule] A stop's impulse j along e's normal changes the kinetic energy by j s + j^2 c / 2,
// s the normal velocity the answering sides see (a tet body's rigid velocity at its vertex) and c
// the compliance: up to -2 s / c it removes energy, and a stop that a tet body answers goes no
// further. Where a vibrating tet body's contact vertex approaches faster than the body moves, the
// full stop of that approach, given to the body rigidly, added 13 J to a bar bouncing on a cloth
// (2.3 bands above H*); the solve and the push after it stop the vertex through its elements.
// Particles answer with the velocities the stop sees, so there s is the approach itself (capping
// it there only cut stops of 1e-21 by round-off, and moved a folding cloth's chaotic run).
double lossOnlyStop(double j, ImpulseMotion& velocity, const ContactEvent& e, double compliance, Exemption x = {}) {
  bool body_answers = false;
  const double s = velocity.answeringAlong(e, x, body_answers);
  return body_answers ? std::min(j, std::max(0.0, -2.0 * s / compliance)) : j;
}

// [project rule] Coulomb friction between the surfaces (docs/method.md, "Self-contact"): the
// pair's relative tangential velocity shrinks by at most mu times the change `normal` (>= 0) the
// impulse just applied made to its normal velocity, and never reverses. Friction removes kinetic
// energy only (an impulse that slows the relative motion it acts along, without reversing it).
void applyFriction(const ContactEvent& e, double mu, double normal, const ImpulseResponse& response,
                   ImpulseMotion& velocity) {
  if (!(mu > 0.0) || !(normal > 0.0)) return;
  const Vec3 relative = velocity.relative(e);
  const Vec3 tangential = relative - e.normal.dot(relative) * e.normal;
  const double slip = tangential.norm();
  if (!(slip > 0.0)) return;
  const Vec3 dir = tangential / slip;
  const double compliance = response.compliance(e, dir);
  if (!(compliance > 0.0)) return;
  velocity.push(e, -std::min(slip, mu * normal) / compliance, dir);
}

// The side of a pair a support stands for, from the held side's view (side 0: the pair's vertex or
// first edge; 1: its triangle or second edge): its contact point at x and as predicted at the step's
// end, and its vertices and weights as a support's "triangle" (a vertex or an edge padded with its
// first vertex at weight 0), for friction.
struct OtherSide {
  Vec3 start = Vec3::Zero(), end = Vec3::Zero();
  std::array<int, 3> vertices{};
  Vec3 weights = Vec3::Zero();
};
int sideOf(const ContactEvent& e, int k) { return k < (e.edge_edge ? 2 : 1) ? 0 : 1; }
OtherSide otherSide(const ContactEvent& e, int held, const PositionRows& x, const Eigen::MatrixX3d& ends) {
  OtherSide other;
  int count = 0;
  for (int k = 0; k < 4; ++k) {
    if (sideOf(e, k) == held) continue;
    const int v = e.vertices[std::size_t(k)];
    const double w = std::abs(e.weights[std::size_t(k)]);
    other.start += w * rowOf(x, v);
    other.end += w * rowOf(ends, v);
    other.vertices[std::size_t(count)] = v;
    other.weights[count++] = w;
  }
  for (int j = count; j < 3; ++j) other.vertices[std::size_t(j)] = other.vertices[0];
  return other;
}

// The compliance of one side of a pair alone: the pair's with the other side's weights zeroed.
double sideCompliance(ContactEvent e, int side, const ImpulseResponse& response) {
  for (int k = 0; k < 4; ++k)
    if (sideOf(e, k) != side) e.weights[std::size_t(k)] = 0.0;
  return response.compliance(e, e.normal);
}

// Each particle's support in the solve (SelfContact::stopApproach), against where the other side
// of its pair is predicted at the step's end (`ends`).
void supportPlanes(const std::vector<ContactEvent>& found, const PositionRows& x, const Eigen::MatrixX3d& ends,
                   double thickness, double reach, const Vec3& up, const ImpulseResponse& response,
                   SupportSurfaces where, std::vector<SupportPlane>& supports) {
  // Per particle the plane with the least room between x and the thickness (slack), the first of equals.
  std::vector<int> chosen(static_cast<std::size_t>(x.rows()), -1);
  std::vector<double> slack;
  for (const ContactEvent& e : found) {
    const double compliance[2] = {sideCompliance(e, 0, response), sideCompliance(e, 1, response)};
    for (int held = 0; held < 2; ++held) {
      // The side held rests on the other one, which stands as a plane fixed for the step:
      // - in any direction where the other side hardly moves for it (a tenth as far: a tet body
      //   far heavier than a cloth, or pinned), in every pair shape. A cloth draped over a tet bar,
      //   held on its top alone, was pushed back after the solve at the bar's sides (H ran 1.35
      //   times the largest kinetic energy above H*); with its vertices held on the bar's faces
      //   alone, the bar's corners and edges poked through its triangles and edges in the solve
      //   and were pushed back by centimetres (H up to 2.4 times the blend's band above H*, within
      //   1.1 with the cloth's triangles and edges held on them too);
      // - with `Everywhere`, also a cloth vertex resting on a triangle against gravity (their
      //   direction within 60 degrees of the vertical, the vertex above): the plane does not give
      //   way, and a vertex under a layer, pulled up against it, stayed trapped under it while its
      //   cloth was dragged away.
      const bool heavy = compliance[held] > 0.0 && compliance[1 - held] <= 0.1 * compliance[held];
      const bool rests = where == SupportSurfaces::Everywhere && held == 0 && !e.edge_edge && e.normal.dot(up) >= 0.5;
      if (!heavy && !rests) continue;
      const Vec3 normal = held == 0 ? e.normal : Vec3(-e.normal);  // the held side's outward direction
      const OtherSide other = otherSide(e, held, x, ends);
      for (int k = 0; k < 4; ++k) {
        if (sideOf(e, k) != held || e.weights[std::size_t(k)] == 0.0) continue;
        const int p = e.vertices[std::size_t(k)];
        // A tet body's particles answer as the body (ImpulseResponse): a support of one would hold it alone.
        if (response.inverseMass(p) == 0.0 || response.solidOf()[std::size_t(p)] >= 0) continue;
        const double gap = normal.dot(rowOf(x, p) - other.end);
        if (!(gap > 0.0)) continue;
        // On a light side, resting or slow contact only: a particle that moves relative to the
        // other side's point by more than the reach within the step is in an impact or a slide,
        // which the impulses answer. A heavy side holds at any speed: a cloth thrown at a tet
        // bar, held only where slow, slid over the bar's faces faster than the reach, crossed
        // them in the solve and was pushed back by centimetres after it (SelfContactRun,
        // AClothDropsOntoATetBarAndDrapesOverIt).
        if (!heavy && (rowOf(ends, p) - rowOf(x, p) - (other.end - other.start)).norm() > reach) continue;
        const double offset = std::min(thickness, gap);
        int& c = chosen[std::size_t(p)];
        if (c >= 0 && !(gap - offset < slack[std::size_t(c)])) continue;
        if (c < 0) {
          c = static_cast<int>(supports.size());
          supports.emplace_back();
          slack.push_back(0.0);
        }
        supports[std::size_t(c)] = SupportPlane{p, other.end + offset * normal, normal, other.vertices, other.weights};
        slack[std::size_t(c)] = gap - offset;
      }
    }
  }
}

}  // namespace

double SelfContact::stopApproach(const PositionRows& x, Eigen::MatrixX3d& v, const Eigen::MatrixX3d& predicted,
                                 double h, const Eigen::VectorXd& masses, const std::vector<int>& fixed,
                                 std::vector<SupportPlane>* supports, const Eigen::Vector3d& fall,
                                 SupportSurfaces where, const Eigen::MatrixX3d* held) const {
  if (supports) supports->clear();
  if (surface_.empty()) return 0.0;
  // What the prediction adds to the velocities' path (gravity, the colliders' projection).
  const Eigen::MatrixX3d drift = supports ? Eigen::MatrixX3d(predicted - x - h * v) : Eigen::MatrixX3d();
  const ImpulseResponse response(solid_of_, solids_, x, masses, fixed, held);
  ImpulseMotion velocity(response, v);
  bool changed = false;
  const double kinetic_before = kinetic(v, masses);
  const std::vector<ContactEvent> found = events(x, predicted, thickness_);
  for (const ContactEvent& e : found) {
    const Share share = approachShare(response, e);
    const double compliance = share.compliance;
    if (!(compliance > 0.0)) continue;
    double gap = 0.0, path = 0.0;
    for (int k = 0; k < 4; ++k) {
      const int i = e.vertices[std::size_t(k)];
      gap += e.weights[std::size_t(k)] * e.normal.dot(rowOf(x, i));
      path += e.weights[std::size_t(k)] * e.normal.dot(rowOf(predicted, i) - rowOf(x, i));
    }
    const double speed = velocity.along(e);
    // The approach the prediction adds to the velocities' (gravity against a supported body).
    const double drift = path / h - speed;
    // The approach speed that ends the step at the thickness with that drift, never a separating one.
    const double wanted = std::min(0.0, (thickness_ - gap) / h - std::min(drift, 0.0));
    if (!(speed < wanted)) continue;
    const double full = (wanted - speed) / compliance;
    const double stop = lossOnlyStop(full, velocity, e, compliance, {share.held});
    if (!(stop > 0.0)) continue;
    velocity.push(e, stop, e.normal, nullptr, {share.held});
    applyFriction(e, friction_, stop == full ? wanted - speed : stop * compliance, response, velocity);
    changed = true;
  }
  velocity.settle();
  if (supports) {
    // The step's ends with the stopped velocities; a tet body's as a rigid body's: its fall, less
    // the most the colliders lift one of its particles against it (a bar lying on the ground stays).
    Eigen::MatrixX3d ends = x + h * v + drift;
    const double f = fall.norm();
    for (const std::vector<int>& body : solids_) {
      double lift = 0.0;
      if (f > 0.0)
        for (int i : body) lift = std::max(lift, -(rowOf(drift, i) - fall).dot(fall) / f);
      const Vec3 move = f > 0.0 ? Vec3(fall * (1.0 - lift / f)) : Vec3::Zero();
      for (int i : body) ends.row(i) = x.row(i) + h * v.row(i) + move.transpose();
    }
    // The step's pairs, and those near at its predicted end (a static query at the ends): within
    // the thickness and the fall under gravity over the step, the gap gravity alone closes. (The
    // colliders' wider margin, contact_tolerance more, cost three times as much on a crumpled pile,
    // and pumped the study scene's dragged pile.)
    const double reach = thickness_ + fall.norm();
    if (!(fall.norm() > 0.0)) return changed ? kinetic_before - kinetic(v, masses) : 0.0;  // nothing rests
    std::vector<ContactEvent> pairs = found;
    const double scale = std::max((x.colwise().maxCoeff() - x.colwise().minCoeff()).maxCoeff(), thickness_);
    for (const auto& [p, t] : candidates(ends, ends, nullptr, reach).vertex_triangle)
      supportPairEvent(x, ends, p, surface_.triangles[std::size_t(t)], reach, scale, pairs);
    supportPlanes(pairs, x, ends, thickness_, reach, Vec3(-fall.normalized()), response, where, *supports);
  }
  return changed ? kinetic_before - kinetic(v, masses) : 0.0;
}

double SelfContact::supportFriction(const std::vector<SupportPlane>& supports, const std::vector<double>& impulses,
                                    const PositionRows& x, Eigen::MatrixX3d& v, const Eigen::VectorXd& masses,
                                    const std::vector<int>& fixed) const {
  if (!(friction_ > 0.0) || supports.empty()) return 0.0;
  const ImpulseResponse response(solid_of_, solids_, x, masses, fixed);
  ImpulseMotion velocity(response, v);
  const double kinetic_before = kinetic(v, masses);
  for (std::size_t i = 0; i < supports.size(); ++i) {
    const SupportPlane& s = supports[i];
    ContactEvent e;
    e.vertices = {s.particle, s.triangle[0], s.triangle[1], s.triangle[2]};
    e.weights = {1.0, -s.bary[0], -s.bary[1], -s.bary[2]};
    e.normal = s.normal;
    applyFriction(e, friction_, impulses[i] * response.inverseMass(s.particle), response, velocity);
  }
  velocity.settle();
  return kinetic_before - kinetic(v, masses);
}

SelfContactResult SelfContact::resolve(const PositionRows& x0, Eigen::MatrixX3d& x1, Eigen::MatrixX3d& v1,
                                       const Eigen::VectorXd& masses, const std::vector<int>& fixed,
                                       const std::function<bool(Eigen::MatrixX3d&)>& keep_out,
                                       const Eigen::Vector3d& up, const Eigen::MatrixX3d* held) const {
  SelfContactResult result;
  if (surface_.empty()) return result;
  const Eigen::Index n = x1.rows();
  // The bodies answer about their positions at the step's end, as the solve left them.
  const Eigen::MatrixX3d reference = x1;
  const ImpulseResponse response(solid_of_, solids_, reference, masses, fixed, held);
  const double kinetic_before = kinetic(v1, masses);

  bool clean = false;
  // The particles the last round moved: a later round checks only their pairs (the others had
  // no event at a stricter threshold and have not changed).
  std::vector<char> moved(static_cast<std::size_t>(n), 0);
  for (int round = 0; round < kRounds && !clean; ++round) {
    // The first round pushes every pair nearer than the thickness out to it; the later ones only
    // those the earlier impulses left at less than half of it, and the crossings.
    const std::vector<ContactEvent> events =
        round == 0 ? this->events(x0, x1, thickness_) : this->events(x0, x1, 0.5 * thickness_, &moved);
    clean = events.empty();
    std::fill(moved.begin(), moved.end(), 0);
    ImpulseMotion position(response, x1), velocity(response, v1);
    // Each pair's position impulse so far and, where a tet body takes a share of its push, how
    // the push answers (0: not swept).
    std::vector<double> pushed(events.size(), 0.0), push_compliance_of(events.size(), 0.0);
    std::vector<const Vec3*> stacked_of(events.size(), nullptr);
    for (std::size_t i = 0; i < events.size(); ++i) {
      const ContactEvent& e = events[i];
      // The velocities' stop is shared by mass, the held side included: the next step's approach
      // stop holds it (held here as well, a bar dropped on a cloth lying on the ground ran 2-5
      // bands above H* at 0-8 m/s, against about one band shared).
      const double compliance = response.compliance(e, e.normal);
      if (!(compliance > 0.0)) continue;
      const double gap = position.along(e), speed = velocity.along(e);
      // [project rule] The positions' push never moves a held side into its collider (its
      // projection would undo the push, and the pair would end in an impact zone), and it goes
      // upwards where the pair is stacked and its upper side is not much heavier than its lower
      // one (a cloth under a tet body, neither held, takes the push shared by mass rather than
      // lifting the body at every step).
      const double held_compliance = response.compliance(e, e.normal, {true});
      const Vec3* stacked = up.isZero() ? nullptr : &up;
      const double push_compliance = stacked ? response.compliance(e, e.normal, {true, stacked}) : held_compliance;
      if (!(push_compliance > 0.0) || push_compliance < 0.5 * (held_compliance - push_compliance)) stacked = nullptr;
      const double moved_compliance = stacked ? push_compliance : held_compliance;
      // Only a tet body's push is swept again (below): a particle's moves no other pair of it.
      bool body_pushed = false;
      for (int k = 0; k < 4; ++k)
        body_pushed = body_pushed || (response.bodyOf(e, k) >= 0 && !response.exempt(e, k, {true, stacked}));
      push_compliance_of[i] = body_pushed ? std::max(0.0, moved_compliance) : 0.0;
      stacked_of[i] = stacked;
      const double push = gap < thickness_ && moved_compliance > 0.0 ? (thickness_ - gap) / moved_compliance : 0.0;
      pushed[i] = push;
      const double full = speed < 0.0 ? -speed / compliance : 0.0;
      const double stop = full > 0.0 ? lossOnlyStop(full, velocity, e, compliance) : 0.0;
      if (push == 0.0 && stop == 0.0) continue;
      ++result.events;
      if (push != 0.0) position.push(e, push, e.normal, &moved, {true, stacked});
      if (stop != 0.0) {
        velocity.push(e, stop, e.normal);
        applyFriction(e, friction_, stop == full ? -speed : stop * compliance, response, velocity);
      }
      result.positions_moved = result.positions_moved || push != 0.0;
      result.velocities_changed = result.velocities_changed || stop != 0.0;
    }
    // [project rule] A tet body's pushes as accumulated impulses (projected Gauss-Seidel): later
    // sweeps take back what a pair's push holds beyond the thickness now that the others have
    // pushed, never below none. One sweep of pushes that only grow lifted a tet bar resting on a
    // cloth 3.5 mm above where it started, each corner's push turning the bar onto the next:
    // potential energy that nothing books, 2 bands above H* at rest. (Swept, the pushes of a
    // cloth's own pile left more pairs to the impact zones, and a folding cloth's BE run went from
    // 37 to 3,500 times its largest kinetic energy above H*.)
    for (int sweep = 0; sweep < kSweeps; ++sweep) {
      double largest = 0.0;
      for (std::size_t i = 0; i < events.size(); ++i) {
        if (!(push_compliance_of[i] > 0.0)) continue;
        const ContactEvent& e = events[i];
        const double total = std::max(0.0, pushed[i] + (thickness_ - position.along(e)) / push_compliance_of[i]);
        if (total == pushed[i]) continue;
        position.push(e, total - pushed[i], e.normal, &moved, {true, stacked_of[i]});
        result.positions_moved = true;
        largest = std::max(largest, std::abs(total - pushed[i]) * push_compliance_of[i]);
        pushed[i] = total;
      }
      if (largest <= kSweepTolerance * thickness_) break;
    }
    position.settle(&moved);
    velocity.settle();
    if (!clean && result.positions_moved && keep_out) {
      const Eigen::MatrixX3d before = x1;
      if (keep_out(x1)) {
        for (Eigen::Index i = 0; i < n; ++i)
          if (x1.row(i) != before.row(i)) moved[std::size_t(i)] = 1;
      }
    }
  }

  // Impact zones: the vertices of the pairs that still cross keep x0 and move on together
  // (mass-weighted mean velocity), zones merging until nothing crosses. A pair whose vertices
  // all keep x0 already is as the last step left it.
  DisjointSets zones(static_cast<int>(n));
  std::vector<char> frozen(static_cast<std::size_t>(n), 0);
  // The first check is of every pair; a later one only of the pairs with a vertex the last
  // zones put back (nothing else moved).
  std::vector<char> put_back;
  while (!clean) {
    bool grew = false;
    const std::vector<char> last = std::move(put_back);
    put_back.assign(static_cast<std::size_t>(n), 0);
    for (const ContactEvent& e : events(x0, x1, 0.0, last.empty() ? nullptr : &last)) {
      if (!e.crossing) continue;
      bool all_frozen = true;
      for (int v : e.vertices) all_frozen = all_frozen && (frozen[std::size_t(v)] || response.inverseMass(v) == 0.0);
      if (all_frozen) continue;
      for (int k = 1; k < 4; ++k) zones.join(e.vertices[std::size_t(k)], e.vertices[0]);
      // A tet body joins a zone whole (put back in part, its elements would invert).
      const auto freeze = [&](int v) {
        if (frozen[std::size_t(v)]) return;
        frozen[std::size_t(v)] = 1;
        put_back[std::size_t(v)] = 1;
        zones.join(v, e.vertices[0]);
        grew = true;
      };
      for (int v : e.vertices) {
        freeze(v);
        const int b = solid_of_[std::size_t(v)];
        if (b >= 0)
          for (int u : solids_[std::size_t(b)]) freeze(u);
      }
    }
    if (!grew) break;
    // Each zone's momentum over its movable mass, in vertex order.
    std::vector<Eigen::Vector3d> momentum(static_cast<std::size_t>(n), Eigen::Vector3d::Zero());
    std::vector<double> mass(static_cast<std::size_t>(n), 0.0);
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!frozen[std::size_t(i)] || response.inverseMass(static_cast<int>(i)) == 0.0) continue;
      const int r = zones.find(static_cast<int>(i));
      momentum[std::size_t(r)] += masses[i] * v1.row(i).transpose();
      mass[std::size_t(r)] += masses[i];
    }
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!frozen[std::size_t(i)]) continue;
      x1.row(i) = x0.row(i);
      if (response.inverseMass(static_cast<int>(i)) == 0.0) continue;
      const int r = zones.find(static_cast<int>(i));
      v1.row(i) = (momentum[std::size_t(r)] / mass[std::size_t(r)]).transpose();
    }
    result.positions_moved = result.velocities_changed = true;
  }
  result.frozen = static_cast<int>(std::count(frozen.begin(), frozen.end(), 1));
  if (result.velocities_changed) result.kinetic_removed = kinetic_before - kinetic(v1, masses);
  return result;
}

}  // namespace stabint
