#pragma once
// Projections shared by several element types (reference, double precision). Their OpenCL twins
// are in kernels/projections.cl.
#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace stabint::projections {

/// The projection of an element whose A x = v is one 3-vector held at a length r (springs,
/// bending hinges), with params = (w, r, unit fallback direction): p = r v/|v|. A v shorter than
/// 1e-12 max(r, 1) has no direction of its own; it projects along the fallback (springs: the
/// rest direction) so that the answer is defined. Returns the energy w/2 (|v| - r)^2, from the
/// length rather than from |v - p|: the same value with one rounding less. Inline: it is the
/// whole projection of the commonest element.
inline double ontoSphere(const double* v, const double* params, double* p) {
  const double r = params[1];
  const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  const bool degenerate = len < 1e-12 * std::max(r, 1.0);
  for (int c = 0; c < 3; ++c) p[c] = degenerate ? r * params[2 + c] : (r / len) * v[c];
  const double stretch = len - r;
  return 0.5 * params[0] * stretch * stretch;
}

/// Nearest rotation R of F in the Frobenius norm: F = U S V^T, R = U V^T, with the column of
/// the smallest singular value flipped when det(U V^T) < 0 (inverted elements get a proper
/// rotation, never a reflection).
Eigen::Matrix3d nearestRotation(const Eigen::Matrix3d& F);

}  // namespace stabint::projections
