#include "contact/contact_rules.hpp"

#include "contact/collider_queries.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace stabint {
namespace {

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

std::vector<int> separatingPairs(const SceneData& scene, const Forcing& forcing, const ContactPart& part, double t0,
                                 const Eigen::MatrixX3d& x0, const Eigen::MatrixX3d& v0, double t,
                                 const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& forces, double rise) {
  std::vector<int> leaving;
  const int block = scene.blockIndex(contactElementType());
  int e = firstContactElement(scene.scene(), part.colliders.first);
  for (int c = part.colliders.first; c < part.colliders.end(); ++c) {
    const Eigen::Vector3d center = scene.scene().colliders[std::size_t(c)].center;
    const Eigen::Vector3d shift0 = forcing.colliderPosition(c, t0) - center;
    const Eigen::Vector3d moved = forcing.colliderPosition(c, t) - forcing.colliderPosition(c, t0);
    const Eigen::Vector3d speed = t > t0 ? Eigen::Vector3d(moved / (t - t0)) : Eigen::Vector3d::Zero();
    const IndexRange particles = colliderParticles(scene.scene(), c);
    for (int j = particles.first; j < particles.end(); ++j, ++e) {
      if (!scene.elementEnabled(block, e)) continue;
      const Eigen::Index r = j - part.first_row;
      // The plane that supports the pair's geometry at x0's nearest point, moving with the
      // collider: its normal is the direction of separation, and a particle that crossed a thin
      // collider within the iterate is below it, not above the far side.
      double g0[kColliderGeometry], plane[kColliderGeometry];
      const Eigen::Vector3d start = x0.row(r).transpose(), now = x.row(r).transpose();
      pairGeometry(scene, block, e, nullptr, shift0, g0);
      supportingPlane(g0, start, plane);
      const Eigen::Vector3d point(plane[kGeometryCenter], plane[kGeometryCenter + 1], plane[kGeometryCenter + 2]);
      const Eigen::Vector3d normal(plane[kGeometryA], plane[kGeometryA + 1], plane[kGeometryA + 2]);
      const double start_height = normal.dot(start - point), height = normal.dot(now - point - moved);
      // Outside at the start and not approaching: a particle arriving (an impact) is pushed out by
      // its pair, and an iterate that overshoots the surface is no separation.
      if (!(start_height >= 0.0) || normal.dot(v0.row(r).transpose() - speed) < 0.0) continue;
      if (height - start_height <= rise) continue;
      // The forces on the particle at the iterate pull it away from the collider (its pair's
      // part is 0 outside): at the solution its contact force would be negative. Inertia is left
      // out, so that a particle that trembles up from its collider, pulled back by gravity and
      // its neighbours, stays (with inertia, a cloth settling on a sphere and the ground trembled
      // with 20x the kinetic energy).
      if (!(normal.dot(forces.row(r).transpose()) > 0.0)) continue;
      double g[kColliderGeometry];
      pairGeometry(scene, block, e, nullptr, shift0 + moved, g);
      const double at[3] = {now[0], now[1], now[2]};
      if (signedDistance(g, at) > 0.0) leaving.push_back(e);
    }
  }
  return leaving;
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

}  // namespace stabint
