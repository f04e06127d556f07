#include "contact/contact_rules.hpp"

#include "elements/contact.hpp"
#include "elements/element_type.hpp"
#include "scene/scene_data.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace stabint {
namespace {

// Calls visit(c, j, p, depth) for each particle j inside collider c at time t, with p the
// closest point outside and depth = |p - x_j| > 0.
template <typename Visit>
void forEachContact(const SceneData& scene, double t, const Eigen::MatrixX3d& x, Visit&& visit) {
  const std::vector<Collider>& colliders = scene.scene().colliders;
  for (std::size_t c = 0; c < colliders.size(); ++c) {
    double g[kColliderGeometry];
    scene.colliderGeometry(static_cast<int>(c), t, g);
    for (Eigen::Index j = 0; j < x.rows(); ++j) {
      const double xj[3] = {x(j, 0), x(j, 1), x(j, 2)};
      double p[3];
      if (!closestPointOutside(g, xj, p)) continue;
      const Eigen::Vector3d pj(p[0], p[1], p[2]);
      const double depth = (pj - x.row(j).transpose()).norm();
      if (depth > 0.0) visit(c, j, pj, depth);
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

ContactSetChange contactSetChange(const SceneData& scene, double t, double h, double margin, const Eigen::MatrixX3d& x,
                                  const Eigen::MatrixX3d& v) {
  ContactSetChange change;
  const std::vector<Collider>& colliders = scene.scene().colliders;
  const int block = scene.blockIndex(contactElementType());
  const int n = scene.numParticles();
  for (std::size_t c = 0; c < colliders.size(); ++c) {
    double now[kColliderGeometry], next[kColliderGeometry];
    scene.colliderGeometry(static_cast<int>(c), t, now);
    scene.colliderGeometry(static_cast<int>(c), t + h, next);
    for (int j = 0; j < n; ++j) {
      const int e = static_cast<int>(c) * n + j;
      const double xj[3] = {x(j, 0), x(j, 1), x(j, 2)};
      const double predicted[3] = {x(j, 0) + h * v(j, 0), x(j, 1) + h * v(j, 1), x(j, 2) + h * v(j, 2)};
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

int applyFriction(const SceneData& scene, double t, double h, const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v,
                  double& removed) {
  const std::vector<Collider>& colliders = scene.scene().colliders;
  const Eigen::VectorXd& m = scene.masses();
  removed = 0.0;
  int changed = 0;
  forEachContact(scene, t, x, [&](std::size_t c, Eigen::Index j, const Eigen::Vector3d& p, double depth) {
    const Collider& collider = colliders[c];
    if (collider.friction == 0.0) return;
    const Eigen::Vector3d normal = (p - x.row(j).transpose()) / depth;
    const Eigen::Vector3d before = v.row(j).transpose();
    const Eigen::Vector3d relative = before - scene.colliderVelocity(static_cast<int>(c), t);
    const Eigen::Vector3d tangential = relative - relative.dot(normal) * normal;
    const double speed = tangential.norm();
    if (!(speed > 0.0)) return;
    // J / m_j = h w_j d / m_j = h stiffness d: the contact force's impulse over the step.
    const double limit = collider.friction * h * collider.stiffness * depth;
    const Eigen::Vector3d after = before - std::min(1.0, limit / speed) * tangential;
    v.row(j) = after.transpose();
    removed += 0.5 * m[j] * (before.squaredNorm() - after.squaredNorm());
    ++changed;
  });
  return changed;
}

int projectOutOfColliders(const SceneData& scene, double t, double tolerance, Eigen::MatrixX3d& x) {
  // A particle pushed out of one collider into another is pushed out of that one in the next
  // sweep; three sweeps settle any corner of two or three shapes we have met, and the last
  // sweep's result stands.
  constexpr int kSweeps = 3;
  int moves = 0;
  for (int sweep = 0; sweep < kSweeps; ++sweep) {
    int moved = 0;
    forEachContact(scene, t, x, [&](std::size_t, Eigen::Index j, const Eigen::Vector3d& p, double depth) {
      if (!(depth > tolerance)) return;
      // Straight toward p, stopping `tolerance` short of it.
      x.row(j) = (p + (x.row(j).transpose() - p) * (tolerance / depth)).transpose();
      ++moved;
    });
    moves += moved;
    if (moved == 0) break;
  }
  return moves;
}

}  // namespace stabint
