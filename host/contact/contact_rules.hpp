#pragma once
// The contact rules per (collider, particle) pair (docs/method.md, "Contact"), stateless: the
// broad phase that picks the pairs whose contact element is active, Coulomb friction on the
// velocities and the final projection of the positions. ContactResolver (contact_resolver.hpp)
// applies them in the step; the contact energy itself is an element (host/elements/contact.cpp)
// and acts inside every solve.
#include "contact/mesh_collider.hpp"
#include "elements/contact.hpp"  // IndexRange

#include <Eigen/Core>

#include <memory>
#include <vector>

namespace stabint {

class Forcing;
class SceneData;

/// Which pairs a rule looks at: those of `colliders` (every collider of the scene, or one batch
/// scene's), each collider with its particles; the host copies it reads have particle
/// first_row + r in row r (0 for the whole scene, the scene's first particle for one batch scene's
/// own rows).
struct ContactPart {
  IndexRange colliders;
  int first_row = 0;
};
/// Every collider of the scene, on the scene's whole host copies.
ContactPart wholeScene(const SceneData& scene);

/// Every rule reads the scene's colliders and contact block from `scene` and where the colliders
/// are at a time from `forcing`.
///
/// The broad phase's change of the contact set of `part` at the start of a step of length h from
/// (x, v) at time t. A contact element (firstContactElement) is active when its flag in the
/// scene's contact block is set. A pair enters when x_j (against collider c at t), its
/// prediction x_j + h v_j (against c at t + h) or the path between them (relative to the
/// collider: swept) passes within `margin` of the collider, inside included; it leaves only when
/// both ends and the path are farther than 8 margins (hysteresis, so the set and the global matrix
/// change rarely; a pair that entered by its path stays while its path still crosses).
struct ContactSetChange {
  std::vector<int> entering, leaving;  // contact element indices, ascending
  bool entered_inside = false;         // a pair entered with x_j already inside: E jumps from 0
  bool empty() const { return entering.empty() && leaving.empty(); }
};
ContactSetChange contactSetChange(const SceneData& scene, const Forcing& forcing, const MeshColliders& meshes,
                                  const ContactPart& part, double t, double h, double margin, const Eigen::MatrixX3d& x,
                                  const Eigen::MatrixX3d& v);

/// The pairs of `part` in the contact set that a solve's iterate carries away from their
/// colliders (docs/method.md, "Contact", "Leaving within the solve"): at the step's start (x0, v0
/// at t0) x_j is outside the plane that supports the pair's geometry at its nearest point and
/// does not approach it (relative to the collider); the iterate x (at t) is outside the pair's
/// geometry and has risen more than `rise` above that plane, moved with the collider; and the
/// `forces` on x_j there (less inertia: SolveContext::ContactChange) pull it away. Ascending.
std::vector<int> separatingPairs(const SceneData& scene, const Forcing& forcing, const ContactPart& part, double t0,
                                 const Eigen::MatrixX3d& x0, const Eigen::MatrixX3d& v0, double t,
                                 const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& forces, double rise);

/// The geometry each pair of `part` in the contact set acts with over a step of length h from
/// (x, v) at time t (docs/method.md, "Contact", "The pair's half-space"), written to its params:
/// - a box or a capsule at rest: the plane that supports it at the surface point nearest to x_j
///   (its own face when inside), or where the path x_j -> x_j + h v_j enters when it goes deeper
///   than a quarter of the way to the collider's middle; the solve then keeps each particle on the
///   side it came from, where the nearest point flips to the far side of a thin plate or rod;
/// - a moving box: the plane of its nearest face for a particle inside;
/// - a sphere at rest: the plane where a deep path enters, or at the nearest point from inside;
/// - every other pair acts with its collider, whose nearest point a draped cloth follows within
///   the step. A plane collider is its own geometry.
/// At x_j a supporting plane's potential is the collider's, and the geometry is a function of
/// (x, v, t) and the set alone, so a restored state gets it back by calling this again. Returns
/// whether a pair's geometry changed: the potential of x may then be lower than before (the
/// collider is convex: its nearest face is never farther than a half-space it supports), and the
/// caller evaluates it again and books the loss. A pair of a mesh collider always acts with a
/// half-space: the plane at the path's entry into the mesh (with the crossed triangle's normal)
/// when the path enters it from outside, else the plane through the surface point nearest to x_j,
/// facing x_j from outside and away from it from inside (docs/method.md, "Mesh colliders").
bool writeHalfSpaces(SceneData& scene, const Forcing& forcing, const MeshColliders& meshes, const ContactPart& part,
                     double t, double h, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v);

/// The work the colliders of `part` that move between t0 and t0 + h do on its pairs in the contact
/// set over a step from positions x0 to x1 (both with part.first_row's rows), in two forms:
/// `midpoint`, each pair's contact force at the midpoint state ((x0 + x1) / 2 against the
/// collider at t0 + h/2) dotted with the collider's displacement, and `split`, the same pairs'
/// share of the forcing rule's sum E(x1, t1) - E(x1, tm) + E(x0, tm) - E(x0, t0) (forcingWork).
/// Both agree while every pair stays inside over the step (the energy is then quadratic in the
/// collider's position and the rule exact); where contact switches on within the step the split
/// sum charges the collider for pushing into x0 as if the particle stayed there, w dc^2 / 8 for a
/// displacement dc, which a stiff pair makes far larger than the work of the force that moved it
/// (docs/method.md, "Contact", "A moving collider's work").
struct ContactWork {
  double midpoint = 0.0;
  double split = 0.0;
};
ContactWork contactWork(const SceneData& scene, const Forcing& forcing, const ContactPart& part, double t0, double h,
                        const Eigen::MatrixX3d& x0, const Eigen::MatrixX3d& x1);

/// Coulomb friction at the end of a step of length h, on the velocities `v` of the particles in
/// contact at positions `x` at time t: for each (collider, particle) of `part` in contact, the tangential
/// velocity relative to the collider's shrinks by at most mu times the normal impulse
/// J = h w_j d (d the depth, w_j the contact weight) over m_j, and never reverses. Returns the
/// number of velocities changed; `removed` receives the kinetic energy removed (negative when a
/// moving collider drags a particle along).
int applyFriction(const SceneData& scene, const Forcing& forcing, const MeshColliders& meshes, const ContactPart& part,
                  double t, double h, const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, double& removed);

/// The final projection over `part`: every particle deeper than `tolerance` (or a quarter of the
/// collider's thinnest size) inside its pair's half-space (a collider, for a pair out of the
/// set; a mesh's own nearest surface point) at time t is moved straight out to that depth (velocities unchanged),
/// colliders in order, repeated while that pushes a particle into an earlier one (at most a few sweeps). Returns the
/// number of moves; `drops`, when given, receives per collider of the part the contact energy the moves took out of its
/// pairs (w_j/2 (d^2 - depth^2), weighing what each collider's restitution keeps).
/// With `start` (the step's start: its time and positions, rows as x's), a pair that acts with its
/// collider itself and whose path from the start crosses into the collider is first moved out of
/// the plane where the path enters, so that nothing pulled through a thin part within a step
/// comes out beyond it (docs/method.md, "Final projection").
struct StepStart {
  double t;
  Eigen::Ref<const Eigen::MatrixX3d, 0, Eigen::OuterStride<>> x;  // a view: a batch scene's rows
};
int projectOutOfColliders(const SceneData& scene, const Forcing& forcing, const MeshColliders& meshes,
                          const ContactPart& part, double t, double tolerance, Eigen::MatrixX3d& x,
                          std::vector<double>* drops = nullptr, const StepStart* start = nullptr);

}  // namespace stabint
