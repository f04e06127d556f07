#include "integrator/contact.hpp"

#include "elements/contact.hpp"
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

}  // namespace

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
