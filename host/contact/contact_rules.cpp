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

// Calls visit(c, j, r, p, depth, e) for each particle j (row r of x) of `part` inside collider c
// at time t, with p the closest point outside, depth = |p - x_j| > 0 and e the pair's contact
// element.
template <typename Visit>
void forEachContact(const SceneData& scene, const Forcing& forcing, const ContactPart& part, double t,
                    const Eigen::MatrixX3d& x, Visit&& visit) {
  int e = firstContactElement(scene.scene(), part.colliders.first);
  for (int c = part.colliders.first; c < part.colliders.end(); ++c) {
    double g[kColliderGeometry];
    forcing.colliderGeometry(c, t, g);
    const IndexRange particles = colliderParticles(scene.scene(), c);
    for (int j = particles.first; j < particles.end(); ++j, ++e) {
      const Eigen::Index r = j - part.first_row;
      const double xj[3] = {x(r, 0), x(r, 1), x(r, 2)};
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
    double g0[kColliderGeometry], gm[kColliderGeometry], g1[kColliderGeometry];
    forcing.colliderGeometry(c, t0, g0);
    forcing.colliderGeometry(c, tm, gm);
    forcing.colliderGeometry(c, t1, g1);
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

int applyFriction(const SceneData& scene, const Forcing& forcing, const ContactPart& part, double t, double h,
                  const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, double& removed) {
  const std::vector<Collider>& colliders = scene.scene().colliders;
  const Eigen::VectorXd& m = scene.masses();
  removed = 0.0;
  int changed = 0;
  const int block = scene.blockIndex(contactElementType());
  forEachContact(scene, forcing, part, t, x,
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

int projectOutOfColliders(const SceneData& scene, const Forcing& forcing, const ContactPart& part, double t,
                          double tolerance, Eigen::MatrixX3d& x) {
  // A particle pushed out of one collider into another is pushed out of that one in the next
  // sweep; three sweeps settle any corner of two or three shapes we have met, and the last
  // sweep's result stands.
  constexpr int kSweeps = 3;
  int moves = 0;
  for (int sweep = 0; sweep < kSweeps; ++sweep) {
    int moved = 0;
    forEachContact(scene, forcing, part, t, x,
                   [&](int, int, Eigen::Index r, const Eigen::Vector3d& p, double depth, int) {
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
