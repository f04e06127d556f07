#include "contact/contact_rules.hpp"

#include "elements/contact.hpp"
#include "elements/element_type.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace stabint {
namespace {

// The geometry contact pair e acts with: in the contact set, its half-space (block params, where
// the collider's reference point is at Collider::center) moved by `shift`, written to `pair`;
// out of it, the collider's geometry `collider`.
const double* pairGeometry(const SceneData& scene, int block, int e, const double* collider,
                           const Eigen::Vector3d& shift, double* pair) {
  if (!scene.elementEnabled(block, e)) return collider;
  const ElementBlock& b = scene.blocks()[static_cast<std::size_t>(block)];
  const double* params = b.params.data() + std::size_t(b.type->shape().params) * std::size_t(e) + kContactGeometry;
  std::copy(params, params + kColliderGeometry, pair);
  translateGeometry(shift, pair);
  return pair;
}

// How far y (in mesh collider `mesh`'s frame) is known to be outside the mesh, without a query:
// its bounding box's distance, or pair e's cached bound; 0 when nothing is known.
double knownOutside(const MeshColliders& meshes, const MeshCollider& mesh, int e, const Eigen::Vector3d& y) {
  return std::max(std::sqrt(mesh.bounds().squaredExteriorDistance(y)), meshes.cache.outside(std::size_t(e), y));
}

// Whether a known bound is beyond `distance` with a slack far above the round-off of either, so
// that the query it saves would surely have said the same.
bool surelyBeyond(double bound, double distance, const Eigen::Vector3d& y) {
  return bound > distance + MeshPairCache::kBoundSlack * (1.0 + distance + y.cwiseAbs().maxCoeff());
}

// The surface point of `mesh` nearest to y, pair e's particle (cached).
MeshCollider::Nearest nearestOf(const MeshColliders& meshes, const MeshCollider& mesh, int e,
                                const Eigen::Vector3d& y) {
  if (const MeshCollider::Nearest* known = meshes.cache.nearest(std::size_t(e), y)) return *known;
  MeshCollider::Nearest n;
  mesh.nearest(y, std::numeric_limits<double>::infinity(), n);
  meshes.cache.record(std::size_t(e), y, n);
  return n;
}

// Calls visit(c, j, r, p, depth, e) for each particle j (row r of x) of `part` inside collider c
// at time t, with p the closest point outside, depth = |p - x_j| > 0 and e the pair's contact
// element.
template <typename Visit>
void forEachContact(const SceneData& scene, const Forcing& forcing, const MeshColliders& meshes,
                    const ContactPart& part, double t, const Eigen::MatrixX3d& x, Visit&& visit) {
  const int block = scene.blockIndex(contactElementType());
  int e = firstContactElement(scene.scene(), part.colliders.first);
  for (int c = part.colliders.first; c < part.colliders.end(); ++c) {
    double collider[kColliderGeometry];
    forcing.colliderGeometry(c, t, collider);
    const Eigen::Vector3d shift = forcing.colliderPosition(c, t) - scene.scene().colliders[std::size_t(c)].center;
    const MeshCollider* mesh = meshes[c];
    const IndexRange particles = colliderParticles(scene.scene(), c);
    for (int j = particles.first; j < particles.end(); ++j, ++e) {
      const Eigen::Index r = j - part.first_row;
      const double xj[3] = {x(r, 0), x(r, 1), x(r, 2)};
      if (mesh && !scene.elementEnabled(block, e)) {
        // A mesh's pair out of the set acts with the mesh itself: the nearest surface point of a
        // particle inside (one the solve pushed in, which the set has not seen yet).
        const Eigen::Vector3d y = x.row(r).transpose() - shift;
        if (surelyBeyond(knownOutside(meshes, *mesh, e, y), 0.0, y)) continue;
        const MeshCollider::Nearest n = nearestOf(meshes, *mesh, e, y);
        if (n.signed_distance < 0.0) visit(c, j, r, Eigen::Vector3d(n.point + shift), -n.signed_distance, e);
        continue;
      }
      double pair[kColliderGeometry];
      const double* g = pairGeometry(scene, block, e, collider, shift, pair);
      double p[3];
      if (!closestPointOutside(g, xj, p)) continue;
      const Eigen::Vector3d pj(p[0], p[1], p[2]);
      const double depth = (pj - x.row(r).transpose()).norm();
      if (depth > 0.0) visit(c, j, r, pj, depth, e);
    }
  }
}

// True when x is within `margin` of the collider `g` (inside included): x is inside the
// collider grown by `margin` (a box by its faces, so a little more near its edges).
bool withinMargin(const double* g, const double* x, double margin) {
  double grown[kColliderGeometry];
  std::copy(g, g + kColliderGeometry, grown);
  const int shape = static_cast<int>(g[kGeometryShape]);
  if (shape == static_cast<int>(ColliderShape::Plane)) {
    for (int c = 0; c < 3; ++c) grown[kGeometryCenter + c] += margin * g[kGeometryA + c];
  } else if (shape == static_cast<int>(ColliderShape::Box)) {
    for (int c = 0; c < 3; ++c) grown[kGeometryA + c] += margin;
  } else {
    grown[kGeometryRadius] += margin;
  }
  double p[3];
  return closestPointOutside(grown, x, p);
}

// The distance from x to the collider's surface, negative inside (the depth).
double signedDistance(const double* g, const double* x) {
  const int shape = static_cast<int>(g[kGeometryShape]);
  const double* center = g + kGeometryCenter;
  const double* a = g + kGeometryA;
  if (shape == static_cast<int>(ColliderShape::Plane))
    return (x[0] - center[0]) * a[0] + (x[1] - center[1]) * a[1] + (x[2] - center[2]) * a[2];
  if (shape == static_cast<int>(ColliderShape::Box)) {
    double outside = 0.0, largest = -std::numeric_limits<double>::infinity();
    for (int c = 0; c < 3; ++c) {
      const double q = std::abs(x[c] - center[c]) - a[c];
      outside += q > 0.0 ? q * q : 0.0;
      largest = std::max(largest, q);
    }
    return std::sqrt(outside) + std::min(largest, 0.0);
  }
  Eigen::Vector3d s(center[0], center[1], center[2]);
  const Eigen::Vector3d xv(x[0], x[1], x[2]);
  if (shape == static_cast<int>(ColliderShape::Capsule)) {
    const Eigen::Vector3d ab = Eigen::Vector3d(a[0], a[1], a[2]) - s;
    const double length2 = ab.squaredNorm();
    const double u = length2 > 0.0 ? std::clamp((xv - s).dot(ab) / length2, 0.0, 1.0) : 0.0;
    s += u * ab;
  }
  return (xv - s).norm() - g[kGeometryRadius];
}

// The plane geometry through `point` with outward unit normal `normal`.
void planeGeometry(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double* plane) {
  plane[kGeometryShape] = static_cast<double>(static_cast<int>(ColliderShape::Plane));
  for (int c = 0; c < 3; ++c) plane[kGeometryCenter + c] = point[c], plane[kGeometryA + c] = normal[c];
  plane[kGeometryRadius] = 0.0;
}

// A plane that supports collider g (the collider lies on its inner side) at the surface point
// nearest to y, inside or outside: a sphere's or a capsule's radial one (through s + r n, n the
// direction from the nearest point s of its axis to y, well conditioned on the surface), a box's
// face nearest to y from inside and the plane through its nearest surface point q facing y from
// outside. A plane collider is its own.
void supportingPlane(const double* g, const Eigen::Vector3d& y, double* plane) {
  const int shape = static_cast<int>(g[kGeometryShape]);
  if (shape == static_cast<int>(ColliderShape::Plane)) {
    std::copy(g, g + kColliderGeometry, plane);
    return;
  }
  const double* center = g + kGeometryCenter;
  const double* a = g + kGeometryA;
  if (shape == static_cast<int>(ColliderShape::Box)) {
    const double yv[3] = {y[0], y[1], y[2]};
    double p[3];
    if (closestPointOutside(g, yv, p)) {  // inside: p moved y along one axis, to its nearest face
      int axis = 0;
      for (int c = 1; c < 3; ++c)
        if (std::abs(p[c] - yv[c]) > std::abs(p[axis] - yv[axis])) axis = c;
      planeGeometry(Eigen::Vector3d(p[0], p[1], p[2]),
                    Eigen::Vector3d::Unit(axis) * (y[axis] < center[axis] ? -1.0 : 1.0), plane);
      return;
    }
    Eigen::Vector3d q;  // the nearest surface point
    for (int c = 0; c < 3; ++c) q[c] = std::clamp(y[c], center[c] - a[c], center[c] + a[c]);
    Eigen::Vector3d d = y - q;
    if (!(d.norm() > 0.0)) {  // y on a face: that face's normal
      int axis = 0;
      for (int c = 1; c < 3; ++c)
        if (std::abs(y[c] - center[c]) - a[c] > std::abs(y[axis] - center[axis]) - a[axis]) axis = c;
      d = Eigen::Vector3d::Unit(axis) * (y[axis] < center[axis] ? -1.0 : 1.0);
    }
    planeGeometry(q, d / d.norm(), plane);
    return;
  }
  // A sphere, or a capsule: about the nearest point s of its axis.
  Eigen::Vector3d s(center[0], center[1], center[2]);
  if (shape == static_cast<int>(ColliderShape::Capsule)) {
    const Eigen::Vector3d ab = Eigen::Vector3d(a[0], a[1], a[2]) - s;
    const double length2 = ab.squaredNorm();
    s += (length2 > 0.0 ? std::clamp((y - s).dot(ab) / length2, 0.0, 1.0) : 0.0) * ab;
  }
  const Eigen::Vector3d r = y - s;
  const Eigen::Vector3d normal = r.norm() > 0.0 ? Eigen::Vector3d(r / r.norm()) : Eigen::Vector3d::UnitY();
  planeGeometry(s + g[kGeometryRadius] * normal, normal, plane);
}

// [project rule] The swept test's searches: golden-section steps for a box's closest approach
// (a convex function of the segment's parameter) and bisection steps for the entry; 60 of each
// take the parameter to 1e-12 of the segment.
constexpr int kSearchSteps = 60;

// The parameter u in [0, 1] of the point of segment a + u d nearest to segment c + w e (w in
// [0, 1]): Ericson's closest points of two segments, well conditioned but for parallel ones,
// where any nearest pair serves.
double closestOnSegment(const Eigen::Vector3d& a, const Eigen::Vector3d& d, const Eigen::Vector3d& c,
                        const Eigen::Vector3d& e) {
  const double dd = d.squaredNorm(), ee = e.squaredNorm();
  if (!(dd > 0.0)) return 0.0;
  const Eigen::Vector3d r = a - c;
  const double f = e.dot(r);
  if (!(ee > 0.0)) return std::clamp(-d.dot(r) / dd, 0.0, 1.0);
  const double de = d.dot(e), dr = d.dot(r), denominator = dd * ee - de * de;
  double u = denominator > 0.0 ? std::clamp((de * f - dr * ee) / denominator, 0.0, 1.0) : 0.0;
  const double w = (de * u + f) / ee;
  if (w < 0.0) u = std::clamp(-dr / dd, 0.0, 1.0);
  if (w > 1.0) u = std::clamp((de - dr) / dd, 0.0, 1.0);
  return u;
}

// The segment from a to b against collider g: the parameter s in [0, 1] where it first meets the
// collider (the signed distance first reaches 0), or, when it stays outside, where it comes
// closest; `distance` gets the signed distance there. A sphere's and a capsule's closest approach
// is closed-form (the nearest point of the path to the center or the axis), a box's a search.
double sweep(const double* g, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double& distance,
             bool* enters = nullptr) {
  const auto f = [&](double s) {
    const Eigen::Vector3d y = a + s * (b - a);
    const double yv[3] = {y[0], y[1], y[2]};
    return signedDistance(g, yv);
  };
  const int shape = static_cast<int>(g[kGeometryShape]);
  const Eigen::Vector3d center(g[kGeometryCenter], g[kGeometryCenter + 1], g[kGeometryCenter + 2]);
  double best = 1.0;
  if (shape == static_cast<int>(ColliderShape::Box)) {
    double lo = 0.0, hi = 1.0, f_best = f(1.0);
    constexpr double kGolden = 0.6180339887498949;
    double s1 = hi - kGolden * (hi - lo), s2 = lo + kGolden * (hi - lo), f1 = f(s1), f2 = f(s2);
    for (int i = 0; i < kSearchSteps && f_best >= 0.0; ++i) {
      if (f1 < f_best) best = s1, f_best = f1;
      if (f2 < f_best) best = s2, f_best = f2;
      if (f1 < f2) {
        hi = s2, s2 = s1, f2 = f1, s1 = hi - kGolden * (hi - lo), f1 = f(s1);
      } else {
        lo = s1, s1 = s2, f1 = f2, s2 = lo + kGolden * (hi - lo), f2 = f(s2);
      }
    }
  } else {
    const Eigen::Vector3d axis =
        shape == static_cast<int>(ColliderShape::Capsule)
            ? Eigen::Vector3d(Eigen::Vector3d(g[kGeometryA], g[kGeometryA + 1], g[kGeometryA + 2]) - center)
            : Eigen::Vector3d(Eigen::Vector3d::Zero());
    best = closestOnSegment(a, b - a, center, axis);
  }
  distance = f(best);
  if (enters) *enters = distance < 0.0;
  if (distance >= 0.0) return best;
  // It enters between 0 (outside) and `best` (inside): the crossing, from the outside.
  double out = 0.0, in = best;
  for (int i = 0; i < kSearchSteps; ++i) {
    const double mid = 0.5 * (out + in);
    (f(mid) < 0.0 ? in : out) = mid;
  }
  distance = f(out);
  return out;
}

// Half the collider's thinnest size: a box's smallest half extent, a radius (a plane: infinite).
double halfThickness(const Collider& collider) {
  if (collider.shape == ColliderShape::Box) return collider.half_extents.minCoeff();
  if (collider.shape == ColliderShape::Plane) return std::numeric_limits<double>::infinity();
  return collider.radius;
}

// How deep the middle of the collider is below its face of outward normal n: a box's half
// extent along the axis n is most aligned with, a radius (a plane: infinite).
double halfDepthBelow(const Collider& collider, const Eigen::Vector3d& n) {
  if (collider.shape != ColliderShape::Box) return halfThickness(collider);
  Eigen::Index axis = 0;
  n.cwiseAbs().maxCoeff(&axis);
  return collider.half_extents[axis];
}

// [project rule] A pair of a collider at rest over the step acts with a half-space when its
// path goes deeper than this part of the way from its face to the collider's middle (it may then
// cross the middle, where the nearest face is the far one), and with the collider itself
// otherwise (a particle inside a box always acts with the box's nearest face): a half-space is
// chosen once per step from the particle's path, and slow contact keeps the collider's own
// nearest point, which follows the particle continuously. (A moving collider keeps its own
// geometry: its half-spaces booked 142 J for the stiff push of 125 J, tests/test_contact.cpp.)
constexpr double kSweptPath = 0.25;

// [project rule] A pair leaves the set only beyond this many margins, so that a body bouncing a
// few centimetres off a collider does not leave the set and come back, refactoring twice
// (docs/method.md, "Contact", has the counts).
constexpr double kLeaveMargins = 8.0;

// contactSetChange's rule for the pairs of mesh collider c (elements from e on).
void meshSetChange(const SceneData& scene, const Forcing& forcing, const MeshColliders& meshes, int c, int e,
                   const ContactPart& part, double t, double h, double margin, const Eigen::MatrixX3d& x,
                   const Eigen::MatrixX3d& v, ContactSetChange& change) {
  const MeshCollider& mesh = *meshes[c];
  const int block = scene.blockIndex(contactElementType());
  const Eigen::Vector3d reference = scene.scene().colliders[std::size_t(c)].center;
  const Eigen::Vector3d now = forcing.colliderPosition(c, t) - reference,
                        next = forcing.colliderPosition(c, t + h) - reference;
  // Whether the path a -> b passes within `distance` of the surface (inside included), as the
  // analytic shapes' swept test: sphere tracing, since the distance to the surface changes by at
  // most the way travelled; a step is at least a quarter of `distance`, so a path that comes
  // within three quarters of it is always found.
  const auto pathNear = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, double distance) {
    const double length = (b - a).norm();
    constexpr int kTraceSteps = 256;
    double travelled = 0.0;
    for (int i = 0; i < kTraceSteps; ++i) {
      const Eigen::Vector3d y = length > 0.0 ? Eigen::Vector3d(a + (travelled / length) * (b - a)) : a;
      MeshCollider::Nearest n;
      if (!mesh.nearest(y, distance + (length - travelled), n)) return false;  // nothing ahead comes near
      if (n.signed_distance < distance) return true;
      if (travelled >= length) return false;
      travelled = std::min(length, travelled + std::max(n.signed_distance - distance, 0.25 * distance));
    }
    return true;  // a path grazing the surface for 256 steps: near enough
  };
  const IndexRange particles = colliderParticles(scene.scene(), c);
  for (int j = particles.first; j < particles.end(); ++j, ++e) {
    const Eigen::Index r = j - part.first_row;
    const Eigen::Vector3d a = x.row(r).transpose() - now;  // in the mesh's frame
    const Eigen::Vector3d predicted = x.row(r).transpose() + h * v.row(r).transpose() - next;
    const double reach = (predicted - a).norm();
    if (scene.elementEnabled(block, e)) {
      // The whole path farther than the leaving distance (known from x_j's when it cannot come
      // that near).
      const double leave = kLeaveMargins * margin;
      const double at_a = nearestOf(meshes, mesh, e, a).signed_distance;
      if (!(at_a < leave) && (surelyBeyond(at_a - reach, leave, a) || !pathNear(a, predicted, leave)))
        change.leaving.push_back(e);
      continue;
    }
    // Both ends beyond the margin and the path short of the surface, known without a query.
    if (surelyBeyond(knownOutside(meshes, mesh, e, a), margin + reach, a)) continue;
    const MeshCollider::Nearest at_a = nearestOf(meshes, mesh, e, a);
    if (!(at_a.signed_distance < margin) && !pathNear(a, predicted, margin)) continue;
    change.entering.push_back(e);
    change.entered_inside = change.entered_inside || at_a.signed_distance < 0.0;
  }
}

}  // namespace

ContactPart wholeScene(const SceneData& scene) {
  return ContactPart{IndexRange{0, static_cast<int>(scene.scene().colliders.size())}, 0};
}

ContactSetChange contactSetChange(const SceneData& scene, const Forcing& forcing, const MeshColliders& meshes,
                                  const ContactPart& part, double t, double h, double margin, const Eigen::MatrixX3d& x,
                                  const Eigen::MatrixX3d& v) {
  ContactSetChange change;
  const int block = scene.blockIndex(contactElementType());
  int e = firstContactElement(scene.scene(), part.colliders.first);
  for (int c = part.colliders.first; c < part.colliders.end(); ++c) {
    if (meshes[c]) {
      meshSetChange(scene, forcing, meshes, c, e, part, t, h, margin, x, v, change);
      e += colliderParticles(scene.scene(), c).count;
      continue;
    }
    double now[kColliderGeometry], next[kColliderGeometry];
    forcing.colliderGeometry(c, t, now);
    forcing.colliderGeometry(c, t + h, next);
    const Eigen::Vector3d moved = forcing.colliderPosition(c, t + h) - forcing.colliderPosition(c, t);
    const IndexRange particles = colliderParticles(scene.scene(), c);
    for (int j = particles.first; j < particles.end(); ++j, ++e) {
      const Eigen::Index r = j - part.first_row;
      const double xj[3] = {x(r, 0), x(r, 1), x(r, 2)};
      const double predicted[3] = {x(r, 0) + h * v(r, 0), x(r, 1) + h * v(r, 1), x(r, 2) + h * v(r, 2)};
      // x_j, its prediction or the path between them (relative to the collider: swept, a fast
      // particle crossing a thin collider within the step with both ends far from it) within
      // `distance` of the collider.
      const auto near = [&](double distance) {
        if (withinMargin(now, xj, distance) || withinMargin(next, predicted, distance)) return true;
        const Eigen::Vector3d a = x.row(r).transpose();
        const Eigen::Vector3d b = a + h * v.row(r).transpose() - moved;
        double closest = distance;
        if (signedDistance(now, xj) - (b - a).norm() < distance) sweep(now, a, b, closest);
        return closest < distance;
      };
      if (scene.elementEnabled(block, e)) {
        // A pair whose path still crosses the collider stays (a pair that entered by its path
        // would otherwise leave when the set is next updated before the step that needs it).
        if (!near(kLeaveMargins * margin)) change.leaving.push_back(e);
        continue;
      }
      if (!near(margin)) continue;
      change.entering.push_back(e);
      double p[3];
      change.entered_inside = change.entered_inside || closestPointOutside(now, xj, p);
    }
  }
  return change;
}

bool writeHalfSpaces(SceneData& scene, const Forcing& forcing, const MeshColliders& meshes, const ContactPart& part,
                     double t, double h, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v) {
  const int block = scene.blockIndex(contactElementType());
  const ElementBlock& contact = scene.blocks()[static_cast<std::size_t>(block)];
  const std::size_t P = static_cast<std::size_t>(contact.type->shape().params);
  bool changed = false;
  const auto write = [&](int e, const double* geometry) {
    const double* current = contact.params.data() + P * std::size_t(e) + kContactGeometry;
    if (std::equal(geometry, geometry + kColliderGeometry, current)) return;
    scene.setElementParams(block, e, kContactGeometry, geometry, kColliderGeometry);
    changed = true;
  };
  int e = firstContactElement(scene.scene(), part.colliders.first);
  for (int c = part.colliders.first; c < part.colliders.end(); ++c) {
    const Collider& collider = scene.scene().colliders[static_cast<std::size_t>(c)];
    if (const MeshCollider* mesh = meshes[c]) {
      // In the mesh's frame (where its reference point is at Collider::center), as the params
      // hold a pair's geometry.
      const Eigen::Vector3d now = forcing.colliderPosition(c, t) - collider.center,
                            next = forcing.colliderPosition(c, t + h) - collider.center;
      const IndexRange particles = colliderParticles(scene.scene(), c);
      for (int j = particles.first; j < particles.end(); ++j, ++e) {
        if (!scene.elementEnabled(block, e)) continue;
        const Eigen::Index r = j - part.first_row;
        const Eigen::Vector3d a = x.row(r).transpose() - now;
        const Eigen::Vector3d b = x.row(r).transpose() + h * v.row(r).transpose() - next;
        double plane[kColliderGeometry], s = 0.0;
        Eigen::Vector3d normal;
        const MeshCollider::Nearest n = nearestOf(meshes, *mesh, e, a);
        // A path from outside that cannot reach the surface enters nowhere.
        const bool may_enter = n.signed_distance >= 0.0 && !surelyBeyond(n.signed_distance, (b - a).norm(), a);
        if (!may_enter || !mesh->firstEntry(a, b, s, normal))
          planeGeometry(n.point, n.normal, plane);
        else
          planeGeometry(a + s * (b - a), normal, plane);
        write(e, plane);
      }
      continue;
    }
    double now[kColliderGeometry], own[kColliderGeometry];
    forcing.colliderGeometry(c, t, now);
    colliderGeometryAt(collider, collider.center, own);
    const Eigen::Vector3d shift = forcing.colliderPosition(c, t) - collider.center;
    const Eigen::Vector3d moved = forcing.colliderPosition(c, t + h) - forcing.colliderPosition(c, t);
    const IndexRange particles = colliderParticles(scene.scene(), c);
    for (int j = particles.first; j < particles.end(); ++j, ++e) {
      if (!scene.elementEnabled(block, e) || collider.shape == ColliderShape::Plane) continue;
      const Eigen::Index r = j - part.first_row;
      const Eigen::Vector3d a = x.row(r).transpose();
      const Eigen::Vector3d b = a + h * v.row(r).transpose() - moved;
      double plane[kColliderGeometry];
      const double* geometry = own;
      const double xj[3] = {a[0], a[1], a[2]};
      const bool inside = signedDistance(now, xj) < 0.0;
      if (moved.isZero(0.0) && (collider.shape == ColliderShape::Box || collider.shape == ColliderShape::Capsule)) {
        // [project rule] A box or a capsule at rest: every pair acts with a plane that supports
        // it, so that the solve itself keeps each particle on the side it came from, where the
        // nearest point flips to the far side halfway through a thin plate or rod (and to a side
        // face at a box's edges): the plane at the surface point nearest to x_j (its own face
        // when inside), or where a path that goes deep enters. At x_j the plane's potential is
        // the collider's (0 outside, the nearest face's depth inside), so the change books
        // nothing. A sphere's pairs keep its curved surface, which a cloth draped over it follows
        // within the step (see the next cases).
        supportingPlane(now, a, plane);
        geometry = plane;
        if (!inside && (b - a).norm() > kSweptPath * halfThickness(collider)) {
          double distance = 0.0;
          bool enters = false;
          const Eigen::Vector3d y = a + sweep(now, a, b, distance, &enters) * (b - a);
          double entry[kColliderGeometry];
          if (enters) {
            supportingPlane(now, y, entry);
            const Eigen::Vector3d normal(entry[kGeometryA], entry[kGeometryA + 1], entry[kGeometryA + 2]);
            if (std::abs((b - a).dot(normal)) > kSweptPath * halfDepthBelow(collider, normal))
              std::copy(entry, entry + kColliderGeometry, plane);
          }
        }
      } else if (inside && collider.shape == ColliderShape::Box) {
        // A moving box: its nearest face, whatever its speed, kept over the step so that no
        // iterate goes out through the far face of a thin box.
        supportingPlane(now, a, plane);
        geometry = plane;
      } else if (moved.isZero(0.0) && (b - a).norm() > kSweptPath * halfThickness(collider)) {
        Eigen::Vector3d y = a;  // inside: x_j; outside: where the path enters
        bool enters = inside;
        if (!enters) {
          double distance = 0.0;
          y = a + sweep(now, a, b, distance, &enters) * (b - a);
        }
        if (enters) {
          supportingPlane(now, y, plane);
          const Eigen::Vector3d normal(plane[kGeometryA], plane[kGeometryA + 1], plane[kGeometryA + 2]);
          if (std::abs((b - a).dot(normal)) > kSweptPath * halfDepthBelow(collider, normal)) geometry = plane;
        }
      }
      if (geometry == plane) translateGeometry(-shift, plane);
      write(e, geometry);
    }
  }
  return changed;
}

ContactWork contactWork(const SceneData& scene, const Forcing& forcing, const ContactPart& part, double t0, double h,
                        const Eigen::MatrixX3d& x0, const Eigen::MatrixX3d& x1) {
  ContactWork work;
  const int block = scene.blockIndex(contactElementType());
  const double t1 = t0 + h, tm = t0 + 0.5 * h;
  int e = firstContactElement(scene.scene(), part.colliders.first);
  for (int c = part.colliders.first; c < part.colliders.end(); ++c) {
    const IndexRange particles = colliderParticles(scene.scene(), c);
    const Eigen::Vector3d displacement = forcing.colliderPosition(c, t1) - forcing.colliderPosition(c, t0);
    if (displacement.isZero(0.0)) {
      e += particles.count;
      continue;
    }
    const Eigen::Vector3d reference = scene.scene().colliders[std::size_t(c)].center;
    const Eigen::Vector3d shift0 = forcing.colliderPosition(c, t0) - reference,
                          shiftm = forcing.colliderPosition(c, tm) - reference,
                          shift1 = forcing.colliderPosition(c, t1) - reference;
    // The pair's energy w/2 |x - p(x)|^2 against geometry g, and its force w (p - x) into f.
    const auto energy = [](const double* g, const double* x, double w, double* f) {
      double p[3];
      closestPointOutside(g, x, p);
      double squared = 0.0;
      for (int i = 0; i < 3; ++i) {
        f[i] = w * (p[i] - x[i]);
        squared += (p[i] - x[i]) * (p[i] - x[i]);
      }
      return 0.5 * w * squared;
    };
    for (int j = particles.first; j < particles.end(); ++j, ++e) {
      const double w = scene.elementWeight(block, e);
      if (w == 0.0) continue;  // out of the contact set
      // The pair's half-space where the collider is at t0, tm and t1.
      double g0[kColliderGeometry], gm[kColliderGeometry], g1[kColliderGeometry];
      pairGeometry(scene, block, e, nullptr, shift0, g0);
      pairGeometry(scene, block, e, nullptr, shiftm, gm);
      pairGeometry(scene, block, e, nullptr, shift1, g1);
      const Eigen::Index r = j - part.first_row;
      const double a[3] = {x0(r, 0), x0(r, 1), x0(r, 2)}, b[3] = {x1(r, 0), x1(r, 1), x1(r, 2)};
      const double m[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
      double f[3];
      work.split += (energy(g1, b, w, f) - energy(gm, b, w, f)) + (energy(gm, a, w, f) - energy(g0, a, w, f));
      energy(gm, m, w, f);
      work.midpoint += f[0] * displacement[0] + f[1] * displacement[1] + f[2] * displacement[2];
    }
  }
  return work;
}

int applyFriction(const SceneData& scene, const Forcing& forcing, const MeshColliders& meshes, const ContactPart& part,
                  double t, double h, const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, double& removed) {
  const std::vector<Collider>& colliders = scene.scene().colliders;
  const Eigen::VectorXd& m = scene.masses();
  removed = 0.0;
  int changed = 0;
  const int block = scene.blockIndex(contactElementType());
  forEachContact(scene, forcing, meshes, part, t, x,
                 [&](int c, int j, Eigen::Index r, const Eigen::Vector3d& p, double depth, int e) {
                   const Collider& collider = colliders[static_cast<std::size_t>(c)];
                   if (collider.friction == 0.0) return;
                   const Eigen::Vector3d normal = (p - x.row(r).transpose()) / depth;
                   const Eigen::Vector3d before = v.row(r).transpose();
                   const Eigen::Vector3d relative = before - forcing.colliderVelocity(c, t);
                   const Eigen::Vector3d tangential = relative - relative.dot(normal) * normal;
                   const double speed = tangential.norm();
                   if (!(speed > 0.0)) return;
                   // J / m_j = h w_j d / m_j: the contact force's impulse over the step, with the pair's weight
                   // in the contact set.
                   const double limit = collider.friction * h * scene.enabledWeight(block, e) / m[j] * depth;
                   const Eigen::Vector3d after = before - std::min(1.0, limit / speed) * tangential;
                   v.row(r) = after.transpose();
                   removed += 0.5 * m[j] * (before.squaredNorm() - after.squaredNorm());
                   ++changed;
                 });
  return changed;
}

namespace {

// [project rule] The path rule of the final projection: a pair that acts with its collider itself
// (out of the set, or a moving collider's) and whose path over the step, x0_j -> x_j relative to
// the collider, crosses into it is moved out of the plane that supports the collider where the
// path enters (or at x0_j's nearest face when x0_j was inside) to `allowed` deep: a particle its
// neighbours pull through a thin part within one step, with no contact in the set to stop it,
// goes back to the face it came in by, where the nearest-point projection would leave it beyond
// the far face, or push it out there. A pair in the set acts with a half-space already.
int projectCrossedPaths(const SceneData& scene, const Forcing& forcing, const MeshColliders& meshes,
                        const ContactPart& part, double t, const std::vector<double>& allowed, const StepStart& start,
                        Eigen::MatrixX3d& x, std::vector<double>* drops) {
  const int block = scene.blockIndex(contactElementType());
  int moves = 0;
  int e = firstContactElement(scene.scene(), part.colliders.first);
  for (int c = part.colliders.first; c < part.colliders.end(); ++c) {
    const Collider& collider = scene.scene().colliders[static_cast<std::size_t>(c)];
    const IndexRange particles = colliderParticles(scene.scene(), c);
    const double depth = allowed[std::size_t(c - part.colliders.first)];
    if (collider.shape == ColliderShape::Plane) {
      e += particles.count;
      continue;
    }
    const Eigen::Vector3d carried = forcing.colliderPosition(c, t) - forcing.colliderPosition(c, start.t);
    const Eigen::Vector3d shift = forcing.colliderPosition(c, t) - collider.center;
    const MeshCollider* mesh = meshes[c];
    double g[kColliderGeometry];
    forcing.colliderGeometry(c, t, g);
    for (int j = particles.first; j < particles.end(); ++j, ++e) {
      const Eigen::Index r = j - part.first_row;
      const Eigen::Vector3d a = start.x.row(r).transpose() + carried, b = x.row(r).transpose();
      const double reach = (b - a).norm();
      double plane[kColliderGeometry];
      if (mesh) {
        if (scene.elementEnabled(block, e)) continue;
        const Eigen::Vector3d am = a - shift, bm = b - shift;  // in the mesh's frame
        if (surelyBeyond(knownOutside(meshes, *mesh, e, am), reach, am)) continue;
        double s = 0.0;
        Eigen::Vector3d normal;
        if (!mesh->firstEntry(am, bm, s, normal)) continue;
        planeGeometry(a + s * (b - a), normal, plane);
      } else {
        double pair[kColliderGeometry];
        if (static_cast<int>(pairGeometry(scene, block, e, g, shift, pair)[kGeometryShape]) ==
            static_cast<int>(ColliderShape::Plane))
          continue;
        const double av[3] = {a[0], a[1], a[2]};
        const double at_a = signedDistance(g, av);
        if (at_a >= reach) continue;  // the path is too short to reach the collider
        if (at_a < 0.0) {
          supportingPlane(g, a, plane);
        } else {
          double distance = 0.0;
          bool enters = false;
          const double s = sweep(g, a, b, distance, &enters);
          if (!enters) continue;
          supportingPlane(g, a + s * (b - a), plane);
        }
      }
      const Eigen::Vector3d point(plane[kGeometryCenter], plane[kGeometryCenter + 1], plane[kGeometryCenter + 2]);
      const Eigen::Vector3d normal(plane[kGeometryA], plane[kGeometryA + 1], plane[kGeometryA + 2]);
      // Only past the collider's middle below that plane, where the nearest point is on the far
      // side: a path that clips a rod's edge and ends beside it, or one that ends on the near side,
      // is the nearest-point projection's (taking it back along the normal stretched the body that
      // wrapped round a 3 cm rod, and the blend could not take that energy out).
      const double d = -(b - point).dot(normal);
      const double middle = mesh ? 0.5 * mesh->thickness() : halfDepthBelow(collider, normal);
      if (!(d > middle) || !(d > depth)) continue;
      if (drops)
        (*drops)[std::size_t(c - part.colliders.first)] +=
            0.5 * scene.elementWeight(block, e) * (d * d - depth * depth);
      x.row(r) = (b + (d - depth) * normal).transpose();
      ++moves;
    }
  }
  return moves;
}

}  // namespace

int projectOutOfColliders(const SceneData& scene, const Forcing& forcing, const MeshColliders& meshes,
                          const ContactPart& part, double t, double tolerance, Eigen::MatrixX3d& x,
                          std::vector<double>* drops, const StepStart* start) {
  const int block = scene.blockIndex(contactElementType());
  if (drops) drops->assign(static_cast<std::size_t>(part.colliders.count), 0.0);
  // [project rule] A particle is left no deeper than a quarter of its collider's thinnest size
  // (half a box's smallest half extent, half a radius) either: the next step's half-space is the
  // face nearest to it, which must be the face it came in by.
  std::vector<double> depth(static_cast<std::size_t>(part.colliders.count));
  for (int c = 0; c < part.colliders.count; ++c) {
    const std::size_t i = std::size_t(part.colliders.first + c);
    const MeshCollider* mesh = meshes[int(i)];
    depth[std::size_t(c)] =
        std::min(tolerance, 0.5 * (mesh ? 0.5 * mesh->thickness() : halfThickness(scene.scene().colliders[i])));
  }
  int moves = start ? projectCrossedPaths(scene, forcing, meshes, part, t, depth, *start, x, drops) : 0;
  // A particle pushed out of one collider into another is pushed out of that one in the next
  // sweep; three sweeps settle any corner of two or three shapes we have met, and the last
  // sweep's result stands.
  constexpr int kSweeps = 3;
  for (int sweep = 0; sweep < kSweeps; ++sweep) {
    int moved = 0;
    forEachContact(scene, forcing, meshes, part, t, x,
                   [&](int c, int, Eigen::Index r, const Eigen::Vector3d& p, double d, int e) {
                     const double allowed = depth[std::size_t(c - part.colliders.first)];
                     if (!(d > allowed)) return;
                     if (drops)
                       (*drops)[std::size_t(c - part.colliders.first)] +=
                           0.5 * scene.enabledWeight(block, e) * (d * d - allowed * allowed);
                     // Straight toward p, stopping `allowed` short of it.
                     x.row(r) = (p + (x.row(r).transpose() - p) * (allowed / d)).transpose();
                     ++moved;
                   });
    moves += moved;
    if (moved == 0) break;
  }
  return moves;
}

}  // namespace stabint
