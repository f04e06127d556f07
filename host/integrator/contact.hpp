#pragma once
// What the step does for contact after the solve (docs/method.md, "Contact"): Coulomb friction on
// the velocities and the final projection of the positions. The contact energy itself is an
// element (host/elements/contact.cpp) and acts inside every solve.
#include <Eigen/Core>

namespace stabint {

class SceneData;

/// Coulomb friction at the end of a step of length h, on the velocities `v` of the particles in
/// contact at positions `x` at time t: for each (collider, particle) in contact, the tangential
/// velocity relative to the collider's shrinks by at most mu times the normal impulse
/// J = h w_j d (d the depth, w_j the contact weight) over m_j, and never reverses. Returns the
/// number of velocities changed; `removed` receives the kinetic energy removed (negative when a
/// moving collider drags a particle along).
int applyFriction(const SceneData& scene, double t, double h, const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v,
                  double& removed);

/// The final projection: every particle deeper than `tolerance` inside a collider at time t is
/// moved straight out to depth `tolerance` (velocities unchanged), colliders in order, repeated
/// while that pushes a particle into an earlier one (at most a few sweeps). Returns the number of
/// moves.
int projectOutOfColliders(const SceneData& scene, double t, double tolerance, Eigen::MatrixX3d& x);

}  // namespace stabint
