#pragma once
// Projections shared by several element types (reference, double precision). Their OpenCL twins
// are in kernels/projections.cl and follow the same algorithms step by step, so that the two
// backends agree to round-off (their thresholds and bounds are declared once, for both, in
// host/common/kernel_constants.hpp).
#include "common/kernel_constants.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "common/simd.hpp"

#include <algorithm>
#include <cmath>

// The element passes of the CPU reference work on kLanes elements side by side (lanes): each
// array of a group holds entry i of element l at [i][l], so that every loop over l is a few whole
// SIMD instructions. The functions that do most of the arithmetic are compiled for AVX-512, AVX2 and
// the baseline, and the loader picks the widest the machine has (GCC/Clang target_clones on
// x86-64 Linux): the library stays one portable binary. Every lane does the scalar function's
// operations in the same order (the build has no FMA contraction: -ffp-contract=off), so a lane's
// result is the scalar one bit for bit on any machine.

namespace stabint::projections {

/// Elements per group in the CPU reference's passes: two AVX-512 vectors of doubles. The rotation's
/// Newton steps are chains of dependent divisions and square roots; two independent vectors per
/// step keep the core's pipelines busy where one waits on its chain, which pays for the lanes
/// that iterate only because the group's slowest does.
inline constexpr int kLanes = 16;

/// The projection of an element whose A x = v is one 3-vector held at a length r (springs,
/// bending hinges), with params = (w, r, unit fallback direction): p = r v/|v|. A v shorter than
/// kDegenerateLength (1e-12) times max(r, 1) has no direction of its own; it projects along the
/// fallback (springs: the rest direction) so that the answer is defined. Returns the energy
/// w/2 (|v| - r)^2, from the length rather than from |v - p|: the same value with one rounding
/// less. Inline: it is the whole projection of the commonest element.
inline double ontoSphere(const double* v, const double* params, double* p) {
  const double r = params[1];
  const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  const bool degenerate = len < kDegenerateLength * std::max(r, 1.0);
  for (int c = 0; c < 3; ++c) p[c] = degenerate ? r * params[2 + c] : (r / len) * v[c];
  const double stretch = len - r;
  return 0.5 * params[0] * stretch * stretch;
}

/// A unit vector orthogonal to the unit vector u (crossed with the axis u is least aligned to):
/// the completion of a basis where the data give no direction.
inline Eigen::Vector3d anyOrthogonal(const Eigen::Vector3d& u) {
  const Eigen::Vector3d a = std::abs(u.x()) <= std::abs(u.y()) && std::abs(u.x()) <= std::abs(u.z())
                                ? Eigen::Vector3d::UnitX()
                            : std::abs(u.y()) <= std::abs(u.z()) ? Eigen::Vector3d::UnitY()
                                                                 : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d w = u.cross(a);
  return w / std::sqrt(w.dot(w));
}

/// Nearest proper rotation r of the 3 x 3 matrix m in the Frobenius norm, both as 9 reals
/// row-major (m[3 i + j] = M_ij). The nearest rotation of M^T is R^T, so a column-major M gives a
/// column-major R (the tet passes its F^T as it is stored). For det M > 0 it is the orthogonal
/// polar factor of M, found by scaled Newton iterations (docs/elements.md, "Rotations"); inverted
/// and nearly flat M (det M <= 1e-6 ||M||^3) take a Jacobi eigen-decomposition of M^T M instead,
/// where the column of the smallest singular value flips (a proper rotation, never a
/// reflection).
void nearestRotation(const double* m, double* r);

/// nearestRotation of kLanes matrices at once: m[i][l] is entry i of matrix l, and r likewise.
/// Lane l is nearestRotation(m_l) bit for bit: the Newton iterations run while any lane has not
/// settled, and a settled lane keeps its value; lanes that need the eigen-decomposition take it
/// one by one afterwards.
/// `work`, when given, receives what the group ran: the benchmarks count its arithmetic from it.
struct RotationWork {
  int iterations = 0;         // Newton iterations of the group (its slowest lane's)
  int scaled_iterations = 0;  // of which with the scaling's square roots and division
  int eigen_lanes = 0;        // lanes that took the eigen-decomposition
};
void nearestRotations(const double (*m)[kLanes], double (*r)[kLanes], RotationWork* work = nullptr);

inline Eigen::Matrix3d nearestRotation(const Eigen::Matrix3d& m) {
  Eigen::Matrix3d r;
  nearestRotation(m.data(), r.data());
  return r;
}

/// The same rotation from Eigen's two-sided Jacobi SVD, M = U S V^T, R = U V^T with the column of
/// the smallest singular value flipped when det(U V^T) < 0: an independent oracle for the tests
/// and the benchmark (the method the tet used before; about ten times slower).
Eigen::Matrix3d nearestRotationBySvd(const Eigen::Matrix3d& m);

}  // namespace stabint::projections
