// Friction and the final projection: the contact rules after the solve (docs/method.md, "Contact",
// "Friction" and "Final projection").
#include "contact/contact_rules.hpp"

#include "contact/collider_queries.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace stabint {

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
