#include "elements/projections.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <cmath>
#include <cstdint>
#include <limits>

namespace stabint::projections {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
// Newton's iteration needs det M > 0; below kFlatVolume times ||M||_F^3 the element is treated as
// flat and takes the eigen-decomposition, which is defined for any M. A bound on the iterations
// (kMaxNewtonIterations), never reached in practice (scaled Newton needs at most about 9 for any
// condition number up to 1/epsilon), keeps every call finite. These bounds are the kernels' too:
// host/common/kernel_constants.hpp declares them for both.

/// c = det(X) X^-T for the 3 x 3 X (rows a, b, c give the rows b x c, c x a, a x b; the same
/// holds for columns, so the layout does not matter); returns det X.
inline double cofactor(const double* x, double* c) {
  c[0] = x[4] * x[8] - x[5] * x[7];
  c[1] = x[5] * x[6] - x[3] * x[8];
  c[2] = x[3] * x[7] - x[4] * x[6];
  c[3] = x[7] * x[2] - x[8] * x[1];
  c[4] = x[8] * x[0] - x[6] * x[2];
  c[5] = x[6] * x[1] - x[7] * x[0];
  c[6] = x[1] * x[5] - x[2] * x[4];
  c[7] = x[2] * x[3] - x[0] * x[5];
  c[8] = x[0] * x[4] - x[1] * x[3];
  return x[0] * c[0] + x[1] * c[1] + x[2] * c[2];
}

/// The orthogonal polar factor of m by Newton's iteration X <- (g X + X^-T / g)/2 (Higham 1986),
/// with Higham's Frobenius-norm scaling g = (||X^-1|| / ||X||)^1/2 while the updates are large.
/// Near convergence the error squares each step, so once an update d = ||X_new - X|| has
/// d^2 < epsilon, X_new is exact to round-off. Returns false (r untouched) when det m is not
/// safely positive or the iteration did not settle.
bool polarByNewton(const double* m, double* r) {
  double x[9], c[9];
  double m2 = 0.0;
  for (int i = 0; i < 9; ++i) m2 += m[i] * m[i];
  for (int i = 0; i < 9; ++i) x[i] = m[i];
  double det = cofactor(x, c);
  if (!(det > kFlatVolume * m2 * std::sqrt(m2))) return false;
  bool scale = true;
  for (int iteration = 0; iteration < kMaxNewtonIterations; ++iteration) {
    double g = 1.0;
    if (scale) {
      double x2 = 0.0, c2 = 0.0;
      for (int i = 0; i < 9; ++i) x2 += x[i] * x[i];
      for (int i = 0; i < 9; ++i) c2 += c[i] * c[i];
      g = std::sqrt(std::sqrt(c2 / x2) / det);
    }
    const double a = 0.5 * g, b = 0.5 / (g * det);
    double update2 = 0.0;
    for (int i = 0; i < 9; ++i) {
      const double next = a * x[i] + b * c[i];
      update2 += (next - x[i]) * (next - x[i]);
      x[i] = next;
    }
    if (update2 < kEpsilon) {
      for (int i = 0; i < 9; ++i) r[i] = x[i];
      return true;
    }
    scale = update2 > kNewtonScaling;
    det = cofactor(x, c);
    if (!(det > 0.0)) return false;
  }
  return false;
}

/// cofactor() of every lane: c[i][l] and det[l] from x[i][l].
template <int W>
inline __attribute__((always_inline)) void cofactors(const double (*x)[W], double (*c)[W], double* det) {
  STABINT_LANES for (int l = 0; l < W; ++l) {
    c[0][l] = x[4][l] * x[8][l] - x[5][l] * x[7][l];
    c[1][l] = x[5][l] * x[6][l] - x[3][l] * x[8][l];
    c[2][l] = x[3][l] * x[7][l] - x[4][l] * x[6][l];
    c[3][l] = x[7][l] * x[2][l] - x[8][l] * x[1][l];
    c[4][l] = x[8][l] * x[0][l] - x[6][l] * x[2][l];
    c[5][l] = x[6][l] * x[1][l] - x[7][l] * x[0][l];
    c[6][l] = x[1][l] * x[5][l] - x[2][l] * x[4][l];
    c[7][l] = x[2][l] * x[3][l] - x[0][l] * x[5][l];
    c[8][l] = x[0][l] * x[4][l] - x[1][l] * x[3][l];
    det[l] = x[0][l] * c[0][l] + x[1][l] * c[1][l] + x[2][l] * c[2][l];
  }
}

/// One Jacobi rotation zeroing A[p][q] of the symmetric A: A <- J^T A J, V <- V J
/// (Golub & Van Loan, sym.schur2).
void jacobiRotate(double* A, double* V, int p, int q) {
  const double apq = A[3 * p + q];
  if (apq == 0.0) return;
  const double tau = (A[3 * q + q] - A[3 * p + p]) / (2 * apq);
  const double t = (tau >= 0 ? 1.0 : -1.0) / (std::abs(tau) + std::sqrt(1 + tau * tau));
  const double c = 1 / std::sqrt(1 + t * t);
  const double s = t * c;
  for (int k = 0; k < 3; ++k) {
    const double akp = A[3 * k + p], akq = A[3 * k + q];
    A[3 * k + p] = c * akp - s * akq;
    A[3 * k + q] = s * akp + c * akq;
  }
  for (int k = 0; k < 3; ++k) {
    const double apk = A[3 * p + k], aqk = A[3 * q + k];
    A[3 * p + k] = c * apk - s * aqk;
    A[3 * q + k] = s * apk + c * aqk;
  }
  A[3 * p + q] = 0;
  A[3 * q + p] = 0;
  for (int k = 0; k < 3; ++k) {
    const double vkp = V[3 * k + p], vkq = V[3 * k + q];
    V[3 * k + p] = c * vkp - s * vkq;
    V[3 * k + q] = s * vkp + c * vkq;
  }
}

/// R = U V^T from F = U S V^T with det U = det V = +1 (so the sign of det F lands on the
/// smallest singular value: the flip). V and S^2 come from a cyclic Jacobi eigen-decomposition
/// of F^T F (sorted descending); U from Gram-Schmidt on F V with u3 = u1 x u2, which stays
/// defined for near-degenerate and inverted F. Row-major arrays.
void rotationByEigen(const double* F, double* R) {
  double A[9], V[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) A[3 * i + j] = F[i] * F[j] + F[3 + i] * F[3 + j] + F[6 + i] * F[6 + j];
  for (int sweep = 0; sweep < kMaxJacobiSweeps; ++sweep) {
    const double off = A[1] * A[1] + A[2] * A[2] + A[5] * A[5];
    const double diag = A[0] * A[0] + A[4] * A[4] + A[8] * A[8];
    if (!(off > kEpsilon * kEpsilon * diag)) break;
    jacobiRotate(A, V, 0, 1);
    jacobiRotate(A, V, 0, 2);
    jacobiRotate(A, V, 1, 2);
  }
  // Sort eigenvalues (squared singular values) descending, columns of V along.
  double e[3] = {A[0], A[4], A[8]};
  for (int pass = 0; pass < 2; ++pass)
    for (int i = 0; i < 2 - pass; ++i)
      if (e[i] < e[i + 1]) {
        std::swap(e[i], e[i + 1]);
        for (int k = 0; k < 3; ++k) std::swap(V[3 * k + i], V[3 * k + i + 1]);
      }
  auto column = [&V](int j) { return Eigen::Vector3d(V[j], V[3 + j], V[6 + j]); };
  const Eigen::Vector3d v1 = column(0), v2 = column(1);
  Eigen::Vector3d v3 = column(2);
  if (v1.cross(v2).dot(v3) < 0) v3 = -v3;

  const Eigen::Vector3d f0(F[0], F[1], F[2]), f1(F[3], F[4], F[5]), f2(F[6], F[7], F[8]);
  const Eigen::Vector3d b1(f0.dot(v1), f1.dot(v1), f2.dot(v1));
  const Eigen::Vector3d b2(f0.dot(v2), f1.dot(v2), f2.dot(v2));
  const double n1 = std::sqrt(b1.dot(b1));
  const Eigen::Vector3d u1 = n1 > 0 ? Eigen::Vector3d(b1 / n1) : Eigen::Vector3d::UnitX();
  // Gram-Schmidt twice keeps u2 orthogonal to u1 when b2 is much shorter than b1.
  Eigen::Vector3d w = b2 - u1.dot(b2) * u1;
  w -= u1.dot(w) * u1;
  const double n2 = std::sqrt(w.dot(w));
  const Eigen::Vector3d u2 = n2 > kEpsilon * n1 ? Eigen::Vector3d(w / n2) : anyOrthogonal(u1);
  const Eigen::Vector3d u3 = u1.cross(u2);
  // R = U V^T = u1 v1^T + u2 v2^T + u3 v3^T.
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R[3 * i + j] = u1[i] * v1[j] + u2[i] * v2[j] + u3[i] * v3[j];
}

}  // namespace

void nearestRotation(const double* m, double* r) {
  if (!polarByNewton(m, r)) rotationByEigen(m, r);
}

// polarByNewton lane by lane, then rotationByEigen for the lanes it refuses. A lane's state is a
// 64-bit integer like its reals, so that the compiler keeps one mask per vector.
STABINT_TARGET_CLONES
void nearestRotations(const double (*m)[kLanes], double (*r)[kLanes], RotationWork* work) {
  constexpr int W = kLanes;
  enum : std::int64_t { kIterating = 0, kSettled = 1, kRefused = 2 };
  double x[9][W], c[9][W], det[W], m2[W], g[W], update2[W];
  std::int64_t state[W], scale[W];
  STABINT_LANES for (int l = 0; l < W; ++l) {
    m2[l] = 0.0;
    for (int i = 0; i < 9; ++i) m2[l] += m[i][l] * m[i][l];
  }
  for (int i = 0; i < 9; ++i) STABINT_LANES for (int l = 0; l < W; ++l) x[i][l] = m[i][l];
  cofactors<W>(x, c, det);
  STABINT_LANES for (int l = 0; l < W; ++l) {
    state[l] = det[l] > kFlatVolume * m2[l] * std::sqrt(m2[l]) ? kIterating : kRefused;
    scale[l] = 1;
  }
  for (int iteration = 0; iteration < kMaxNewtonIterations; ++iteration) {
    std::int64_t iterating = 0, scaling = 0;
#if defined(STABINT_OMP_SIMD)
#pragma omp simd reduction(| : iterating, scaling)
#endif
    for (int l = 0; l < W; ++l) {
      iterating |= state[l] == kIterating;
      scaling |= state[l] == kIterating && scale[l];
    }
    if (!iterating) break;
    if (work) {
      ++work->iterations;
      work->scaled_iterations += scaling != 0;
    }
    STABINT_LANES for (int l = 0; l < W; ++l) {
      g[l] = 1.0;
      update2[l] = 0.0;
    }
    // The scaling's square roots and division are most of an iteration's cost in SIMD: skipped
    // once no lane scales.
    if (scaling) STABINT_LANES for (int l = 0; l < W; ++l) {
        double x2 = 0.0, c2 = 0.0;
        for (int i = 0; i < 9; ++i) x2 += x[i][l] * x[i][l];
        for (int i = 0; i < 9; ++i) c2 += c[i][l] * c[i][l];
        g[l] = scale[l] ? std::sqrt(std::sqrt(c2 / x2) / det[l]) : 1.0;
      }
    for (int i = 0; i < 9; ++i) STABINT_LANES for (int l = 0; l < W; ++l) {
        const double a = 0.5 * g[l], b = 0.5 / (g[l] * det[l]);
        const double next = a * x[i][l] + b * c[i][l];
        update2[l] += (next - x[i][l]) * (next - x[i][l]);
        x[i][l] = state[l] == kIterating ? next : x[i][l];
      }
    STABINT_LANES for (int l = 0; l < W; ++l) {
      const bool settles = state[l] == kIterating && update2[l] < kEpsilon;
      scale[l] = update2[l] > kNewtonScaling;
      state[l] = settles ? kSettled : state[l];
    }
    cofactors<W>(x, c, det);
    STABINT_LANES for (int l = 0; l < W; ++l) state[l] =
        state[l] == kIterating && !(det[l] > 0.0) ? kRefused : state[l];
  }
  for (int i = 0; i < 9; ++i) STABINT_LANES for (int l = 0; l < W; ++l) r[i][l] = x[i][l];
  for (int l = 0; l < W; ++l) {
    if (state[l] == kSettled) continue;
    if (work) ++work->eigen_lanes;
    double ml[9], rl[9];
    for (int i = 0; i < 9; ++i) ml[i] = m[i][l];
    rotationByEigen(ml, rl);
    for (int i = 0; i < 9; ++i) r[i][l] = rl[i];
  }
}

Eigen::Matrix3d nearestRotationBySvd(const Eigen::Matrix3d& m) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU();
  const Eigen::Matrix3d V = svd.matrixV();
  // Singular values are sorted descending, so column 2 belongs to the smallest one.
  if ((U * V.transpose()).determinant() < 0.0) U.col(2) *= -1.0;
  return U * V.transpose();
}

}  // namespace stabint::projections
