#pragma once
// Element math of the CPU reference backend: small stateless functions, one group per element
// type, each with the formula it computes (method.md section 1). Every element has the
// Projective-Dynamics form E = w/2 ||A x - p||^2 with p the projection of A x onto the rest set,
// so its gradient is w A^T (A x - p) and its right-hand-side contribution is w A^T p.
// The OpenCL kernels (kernels/*.cl) hold the same math for the device.
#include <Eigen/Core>

#include <algorithm>

namespace stabint {
namespace elements {

// ---- spring (a, b, rest length r, stiffness k): A x = x_a - x_b, w = k -------------------------

/// p = r d/|d| with d = x_a - x_b. Coincident endpoints (|d| below 1e-12 max(r, 1)) have no
/// direction of their own; they project along `rest_direction` (unit) so the answer is defined.
inline Eigen::Vector3d projectSpring(const Eigen::Vector3d& d, double rest_length,
                                     const Eigen::Vector3d& rest_direction) {
  const double len = d.norm();
  if (len < 1e-12 * std::max(rest_length, 1.0)) return rest_length * rest_direction;
  return (rest_length / len) * d;
}

/// E = k/2 (|d| - r)^2
inline double springEnergy(const Eigen::Vector3d& d, double rest_length, double stiffness) {
  const double stretch = d.norm() - rest_length;
  return 0.5 * stiffness * stretch * stretch;
}

// ---- tet strain: A x = F = Ds Dm^-1 = X G, w = k V -----------------------------------------------

/// G = [[-1,-1,-1],[1,0,0],[0,1,0],[0,0,1]] Dm^-1 (4x3), so that F = X G for X = [x0 x1 x2 x3].
inline Eigen::Matrix<double, 4, 3> tetGradientOperator(const Eigen::Matrix3d& dm_inverse) {
  Eigen::Matrix<double, 4, 3> g;
  g.row(0) = -dm_inverse.colwise().sum();
  g.bottomRows<3>() = dm_inverse;
  return g;
}

/// Nearest rotation R of F in the Frobenius norm: F = U S V^T, R = U V^T, with the column of
/// the smallest singular value flipped when det(U V^T) < 0 (inverted elements get a proper
/// rotation, never a reflection).
Eigen::Matrix3d nearestRotation(const Eigen::Matrix3d& F);

/// E = w/2 ||F - R||_F^2
inline double tetEnergy(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R, double weight) {
  return 0.5 * weight * (F - R).squaredNorm();
}

// ---- pin (vertex j, target q, stiffness k): A x = x_j, p = q, w = k --------------------------------

/// E = k/2 |x - q|^2
inline double pinEnergy(const Eigen::Vector3d& x, const Eigen::Vector3d& q, double stiffness) {
  return 0.5 * stiffness * (x - q).squaredNorm();
}

}  // namespace elements
}  // namespace stabint
