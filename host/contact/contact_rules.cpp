#include "contact/contact_rules.hpp"

#include "elements/contact.hpp"
#include "elements/element_type.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace stabint {
namespace {

// Calls visit(c, j, r, p, depth) for each particle j (row r of x) of `part` inside collider c at
// time t, with p the closest point outside and depth = |p - x_j| > 0.
template <typename Visit>
void forEachContact(const SceneData& scene, const Forcing& forcing, const ContactPart& part, double t,
                    const Eigen::MatrixX3d& x, Visit&& visit) {
  for (int c = part.colliders.first; c < part.colliders.end(); ++c) {
    double g[kColliderGeometry];
    forcing.colliderGeometry(c, t, g);
    const IndexRange particles = colliderParticles(scene.scene(), c);
    for (int j = particles.first; j < particles.end(); ++j) {
      const Eigen::Index r = j - part.first_row;
      const double xj[3] = {x(r, 0), x(r, 1), x(r, 2)};
      double p[3];
      if (!closestPointOutside(g, xj, p)) continue;
      const Eigen::Vector3d pj(p[0], p[1], p[2]);
      const double depth = (pj - x.row(r).transpose()).norm();
      if (depth > 0.0) visit(c, j, r, pj, depth);
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

// [project rule] A pair leaves the set only beyond this many margins, so that a body bouncing a
// few centimetres off a collider does not leave the set and come back, refactoring twice
// (docs/method.md, "Contact", has the counts).
constexpr double kLeaveMargins = 8.0;

}  // namespace

ContactPart wholeScene(const SceneData& scene) {
  return ContactPart{IndexRange{0, static_cast<int>(scene.scene().colliders.size())}, 0};
}

ContactSetChange contactSetChange(const SceneData& scene, const Forcing& forcing, const ContactPart& part, double t,
                                  double h, double margin, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v) {
  ContactSetChange change;
  const int block = scene.blockIndex(contactElementType());
  int e = firstContactElement(scene.scene(), part.colliders.first);
  for (int c = part.colliders.first; c < part.colliders.end(); ++c) {
    double now[kColliderGeometry], next[kColliderGeometry];
    forcing.colliderGeometry(c, t, now);
    forcing.colliderGeometry(c, t + h, next);
    const IndexRange particles = colliderParticles(scene.scene(), c);
    for (int j = particles.first; j < particles.end(); ++j, ++e) {
      const Eigen::Index r = j - part.first_row;
      const double xj[3] = {x(r, 0), x(r, 1), x(r, 2)};
      const double predicted[3] = {x(r, 0) + h * v(r, 0), x(r, 1) + h * v(r, 1), x(r, 2) + h * v(r, 2)};
      if (scene.elementEnabled(block, e)) {
        if (!withinMargin(now, xj, kLeaveMargins * margin) && !withinMargin(next, predicted, kLeaveMargins * margin))
          change.leaving.push_back(e);
      } else if (withinMargin(now, xj, margin) || withinMargin(next, predicted, margin)) {
        change.entering.push_back(e);
        double p[3];
        change.entered_inside = change.entered_inside || closestPointOutside(now, xj, p);
      }
    }
  }
  return change;
}

int applyFriction(const SceneData& scene, const Forcing& forcing, const ContactPart& part, double t, double h,
                  const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, double& removed) {
  const std::vector<Collider>& colliders = scene.scene().colliders;
  const Eigen::VectorXd& m = scene.masses();
  removed = 0.0;
  int changed = 0;
  forEachContact(scene, forcing, part, t, x, [&](int c, int j, Eigen::Index r, const Eigen::Vector3d& p, double depth) {
    const Collider& collider = colliders[static_cast<std::size_t>(c)];
    if (collider.friction == 0.0) return;
    const Eigen::Vector3d normal = (p - x.row(r).transpose()) / depth;
    const Eigen::Vector3d before = v.row(r).transpose();
    const Eigen::Vector3d relative = before - forcing.colliderVelocity(c, t);
    const Eigen::Vector3d tangential = relative - relative.dot(normal) * normal;
    const double speed = tangential.norm();
    if (!(speed > 0.0)) return;
    // J / m_j = h w_j d / m_j = h stiffness d: the contact force's impulse over the step.
    const double limit = collider.friction * h * collider.stiffness * depth;
    const Eigen::Vector3d after = before - std::min(1.0, limit / speed) * tangential;
    v.row(r) = after.transpose();
    removed += 0.5 * m[j] * (before.squaredNorm() - after.squaredNorm());
    ++changed;
  });
  return changed;
}

int projectOutOfColliders(const SceneData& scene, const Forcing& forcing, const ContactPart& part, double t,
                          double tolerance, Eigen::MatrixX3d& x) {
  // A particle pushed out of one collider into another is pushed out of that one in the next
  // sweep; three sweeps settle any corner of two or three shapes we have met, and the last
  // sweep's result stands.
  constexpr int kSweeps = 3;
  int moves = 0;
  for (int sweep = 0; sweep < kSweeps; ++sweep) {
    int moved = 0;
    forEachContact(scene, forcing, part, t, x, [&](int, int, Eigen::Index r, const Eigen::Vector3d& p, double depth) {
      if (!(depth > tolerance)) return;
      // Straight toward p, stopping `tolerance` short of it.
      x.row(r) = (p + (x.row(r).transpose() - p) * (tolerance / depth)).transpose();
      ++moved;
    });
    moves += moved;
    if (moved == 0) break;
  }
  return moves;
}

}  // namespace stabint
