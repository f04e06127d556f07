#pragma once
// Momentum-preserving velocity damping per body (docs/method.md section 6, after Mueller et al. 2007,
// Position Based Dynamics): each velocity moves toward the body's rigid velocity
// v_cm + omega x r_j (omega = I^-1 L) by the body's factor kd in [0, 1]. Linear and angular
// momentum of each body are unchanged; kd = 0 leaves the velocities untouched.
#include <stabint/scene.hpp>

#include <Eigen/Core>

#include <vector>

namespace stabint {

/// Damps `velocities` (`n by 3`) in place and returns the kinetic energy removed (>= 0).
double applyMomentumPreservingDamping(const std::vector<Body>& bodies, const Eigen::VectorXd& masses,
                                      const Eigen::MatrixX3d& positions, Eigen::MatrixX3d& velocities);

}  // namespace stabint
