#pragma once
// Projections shared by several element types (reference, double precision). Their OpenCL twins
// are in kernels/projections.cl.
#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace stabint::projections {

/// Projection of v (3 reals) onto the sphere |p| = radius: p = radius v/|v|. A v shorter than
/// 1e-12 max(radius, 1) has no direction of its own; it projects along the unit `fallback` so
/// that the answer is defined (springs: the rest direction). Returns |v|. Inline: it is the whole
/// projection of the commonest element.
inline double ontoSphere(const double* v, double radius, const double* fallback, double* p) {
  const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (len < 1e-12 * std::max(radius, 1.0)) {
    for (int c = 0; c < 3; ++c) p[c] = radius * fallback[c];
  } else {
    const double scale = radius / len;
    for (int c = 0; c < 3; ++c) p[c] = scale * v[c];
  }
  return len;
}

/// Nearest rotation R of F in the Frobenius norm: F = U S V^T, R = U V^T, with the column of
/// the smallest singular value flipped when det(U V^T) < 0 (inverted elements get a proper
/// rotation, never a reflection).
Eigen::Matrix3d nearestRotation(const Eigen::Matrix3d& F);

}  // namespace stabint::projections
