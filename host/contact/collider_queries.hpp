#pragma once
// Geometric queries of the collider pairs that the contact rules share (host/contact/contact_rules.cpp
// before and within the solve, host/contact/contact_corrections.cpp after it): a pair's geometry,
// signed distances, supporting planes, swept segments and the cached mesh queries.
#include "contact/contact_rules.hpp"
#include "elements/contact.hpp"
#include "elements/element_type.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"

#include <stabint/scene.hpp>

#include <Eigen/Core>

namespace stabint {

// The geometry contact pair e acts with: in the contact set, its half-space (block params, where
// the collider's reference point is at Collider::center) moved by `shift`, written to `pair`;
// out of it, the collider's geometry `collider`.
const double* pairGeometry(const SceneData& scene, int block, int e, const double* collider,
                           const Eigen::Vector3d& shift, double* pair);

// How far y (in mesh collider `mesh`'s frame) is known to be outside the mesh, without a query:
// its bounding box's distance, or pair e's cached bound; 0 when nothing is known.
double knownOutside(const MeshColliders& meshes, const MeshCollider& mesh, int e, const Eigen::Vector3d& y);

// Whether a known bound is beyond `distance` with a slack far above the round-off of either, so
// that the query it saves would surely have said the same.
bool surelyBeyond(double bound, double distance, const Eigen::Vector3d& y);

// The surface point of `mesh` nearest to y, pair e's particle (cached).
MeshCollider::Nearest nearestOf(const MeshColliders& meshes, const MeshCollider& mesh, int e, const Eigen::Vector3d& y);

// True when x is within `margin` of the collider `g` (inside included): x is inside the
// collider grown by `margin` (a box by its faces, so a little more near its edges).
bool withinMargin(const double* g, const double* x, double margin);

// The distance from x to the collider's surface, negative inside (the depth).
double signedDistance(const double* g, const double* x);

// The plane geometry through `point` with outward unit normal `normal`.
void planeGeometry(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double* plane);

// A plane that supports collider g (the collider lies on its inner side) at the surface point
// nearest to y, inside or outside: a sphere's or a capsule's radial one (through s + r n, n the
// direction from the nearest point s of its axis to y, well conditioned on the surface), a box's
// face nearest to y from inside and the plane through its nearest surface point q facing y from
// outside. A plane collider is its own.
void supportingPlane(const double* g, const Eigen::Vector3d& y, double* plane);

// The segment from a to b against collider g: the parameter s in [0, 1] where it first meets the
// collider (the signed distance first reaches 0), or, when it stays outside, where it comes
// closest; `distance` gets the signed distance there. A sphere's and a capsule's closest approach
// is closed-form (the nearest point of the path to the center or the axis), a box's a search.
double sweep(const double* g, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double& distance,
             bool* enters = nullptr);

// Half the collider's thinnest size: a box's smallest half extent, a radius (a plane: infinite).
double halfThickness(const Collider& collider);

// How deep the middle of the collider is below its face of outward normal n: a box's half
// extent along the axis n is most aligned with, a radius (a plane: infinite).
double halfDepthBelow(const Collider& collider, const Eigen::Vector3d& n);
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

}  // namespace stabint
