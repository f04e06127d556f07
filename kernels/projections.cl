// Projections shared by several element types; the OpenCL twins of host/elements/projections.cpp.
// Small matrices are private arrays, row-major: m[3 * row + col].

/// The projection of an element whose A x = v is one 3-vector held at a length r (springs,
/// bending hinges), with params = (w, r, unit fallback direction): p = r v/|v|, along the
/// fallback when |v| < DEGENERATE_LENGTH max(r, 1). Returns the energy w/2 (|v| - r)^2. Written
/// without branches on scalar components: PoCL then vectorizes the work-item loop.
inline real ontoSphere(const real* v, __global const real* params, real* p) {
  const real r = params[1];
  const real len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  const bool degenerate = len < DEGENERATE_LENGTH * fmax(r, (real)1);
  const real scale = degenerate ? (real)0 : r / len;
  p[0] = degenerate ? r * params[2] : scale * v[0];
  p[1] = degenerate ? r * params[3] : scale * v[1];
  p[2] = degenerate ? r * params[4] : scale * v[2];
  const real stretch = len - r;
  return (real)0.5 * params[0] * stretch * stretch;
}

/// w/2 ||a - b||^2 over `count` reals: the energy of an element whose type has no form of its own.
inline real halfWeightedSquaredDistance(real w, const real* a, const real* b, int count) {
  real sum = 0;
#pragma unroll
  for (int i = 0; i < count; ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
  return (real)0.5 * w * sum;
}

// Newton's polar iteration needs det M > 0; below FLAT_VOLUME times ||M||_F^3 the element counts
// as flat and takes rotationByEigen. The bound MAX_NEWTON_ITERATIONS is never reached in practice.
// (FLAT_VOLUME, NEWTON_SCALING, MAX_NEWTON_ITERATIONS and MAX_JACOBI_SWEEPS are the prelude's:
// the CPU reference's values, host/common/kernel_constants.hpp.)

/// c = det(X) X^-T (rows a, b, c of X give the rows b x c, c x a, a x b; the same for columns,
/// so the layout does not matter); returns det X.
inline real cofactor3(const real* x, real* c) {
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

/// The orthogonal polar factor of m by Newton's iteration X <- (g X + X^-T / g)/2 with Higham's
/// Frobenius-norm scaling while the updates are large; done once an update d has
/// d^2 < epsilon (the error squares each step). False (r untouched) when det m is not safely
/// positive or the iteration did not settle.
inline bool polarByNewton(const real* m, real* r) {
  real x[9], c[9];
  real m2 = 0;
#pragma unroll
  for (int i = 0; i < 9; ++i) m2 += m[i] * m[i];
#pragma unroll
  for (int i = 0; i < 9; ++i) x[i] = m[i];
  real det = cofactor3(x, c);
  if (!(det > FLAT_VOLUME * m2 * sqrt(m2))) return false;
  bool scale = true;
  for (int iteration = 0; iteration < MAX_NEWTON_ITERATIONS; ++iteration) {
    real g = 1;
    if (scale) {
      real x2 = 0, c2 = 0;
#pragma unroll
      for (int i = 0; i < 9; ++i) x2 += x[i] * x[i];
#pragma unroll
      for (int i = 0; i < 9; ++i) c2 += c[i] * c[i];
      g = sqrt(sqrt(c2 / x2) / det);
    }
    const real a = (real)0.5 * g, b = (real)0.5 / (g * det);
    real update2 = 0;
#pragma unroll
    for (int i = 0; i < 9; ++i) {
      const real next = a * x[i] + b * c[i];
      update2 += (next - x[i]) * (next - x[i]);
      x[i] = next;
    }
    if (update2 < REAL_EPSILON) {
#pragma unroll
      for (int i = 0; i < 9; ++i) r[i] = x[i];
      return true;
    }
    scale = update2 > NEWTON_SCALING;
    det = cofactor3(x, c);
    if (!(det > 0)) return false;
  }
  return false;
}

/// One Jacobi rotation zeroing A[p][q] of the symmetric A: A <- J^T A J, V <- V J
/// (Golub & Van Loan, sym.schur2).
inline void jacobiRotate(real* A, real* V, int p, int q) {
  const real apq = A[3 * p + q];
  if (apq == (real)0) return;
  const real tau = (A[3 * q + q] - A[3 * p + p]) / (2 * apq);
  const real t = (tau >= 0 ? (real)1 : (real)-1) / (fabs(tau) + sqrt(1 + tau * tau));
  const real c = 1 / sqrt(1 + t * t);
  const real s = t * c;
  for (int k = 0; k < 3; ++k) {
    const real akp = A[3 * k + p], akq = A[3 * k + q];
    A[3 * k + p] = c * akp - s * akq;
    A[3 * k + q] = s * akp + c * akq;
  }
  for (int k = 0; k < 3; ++k) {
    const real apk = A[3 * p + k], aqk = A[3 * q + k];
    A[3 * p + k] = c * apk - s * aqk;
    A[3 * q + k] = s * apk + c * aqk;
  }
  A[3 * p + q] = 0;
  A[3 * q + p] = 0;
  for (int k = 0; k < 3; ++k) {
    const real vkp = V[3 * k + p], vkq = V[3 * k + q];
    V[3 * k + p] = c * vkp - s * vkq;
    V[3 * k + q] = s * vkp + c * vkq;
  }
}

inline real3 column3(const real* M, int j) { return (real3)(M[j], M[3 + j], M[6 + j]); }

inline void swapColumns(real* M, int a, int b) {
  for (int k = 0; k < 3; ++k) {
    const real t = M[3 * k + a];
    M[3 * k + a] = M[3 * k + b];
    M[3 * k + b] = t;
  }
}

/// M = a p^T + b q^T + c r^T (row-major 3x3).
inline void sumOfOuterProducts(real3 a, real3 p, real3 b, real3 q, real3 c, real3 r, real* M) {
  const real3 m0 = a.x * p + b.x * q + c.x * r;
  const real3 m1 = a.y * p + b.y * q + c.y * r;
  const real3 m2 = a.z * p + b.z * q + c.z * r;
  M[0] = m0.x; M[1] = m0.y; M[2] = m0.z;
  M[3] = m1.x; M[4] = m1.y; M[5] = m1.z;
  M[6] = m2.x; M[7] = m2.y; M[8] = m2.z;
}

/// A unit vector orthogonal to the unit vector u (crossed with the axis u is least aligned to).
inline real3 anyOrthogonal(real3 u) {
  const real3 a = fabs(u.x) <= fabs(u.y) && fabs(u.x) <= fabs(u.z) ? (real3)(1, 0, 0)
                  : fabs(u.y) <= fabs(u.z)                          ? (real3)(0, 1, 0)
                                                                    : (real3)(0, 0, 1);
  const real3 w = cross(u, a);
  return w / norm3(w);
}

/// R = U V^T from F = U S V^T with det U = det V = +1 (so the sign of det F lands on the
/// smallest singular value: the "flip" of docs/elements.md). V and S^2 come from a cyclic Jacobi
/// eigen-decomposition of F^T F (sorted descending); U from Gram-Schmidt on F V with
/// u3 = u1 x u2, which stays defined for near-degenerate and inverted F.
inline void rotationByEigen(const real* F, real* R) {
  real A[9], V[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      A[3 * i + j] = F[i] * F[j] + F[3 + i] * F[3 + j] + F[6 + i] * F[6 + j];
  for (int sweep = 0; sweep < MAX_JACOBI_SWEEPS; ++sweep) {
    const real off = A[1] * A[1] + A[2] * A[2] + A[5] * A[5];
    const real diag = A[0] * A[0] + A[4] * A[4] + A[8] * A[8];
    if (!(off > REAL_EPSILON * REAL_EPSILON * diag)) break;
    jacobiRotate(A, V, 0, 1);
    jacobiRotate(A, V, 0, 2);
    jacobiRotate(A, V, 1, 2);
  }
  // Sort eigenvalues (squared singular values) descending, columns of V along.
  real e[3] = {A[0], A[4], A[8]};
  for (int pass = 0; pass < 2; ++pass)
    for (int i = 0; i < 2 - pass; ++i)
      if (e[i] < e[i + 1]) {
        const real t = e[i];
        e[i] = e[i + 1];
        e[i + 1] = t;
        swapColumns(V, i, i + 1);
      }
  const real3 v1 = column3(V, 0), v2 = column3(V, 1);
  real3 v3 = column3(V, 2);
  if (dot(cross(v1, v2), v3) < 0) v3 = -v3;

  const real3 f0 = (real3)(F[0], F[1], F[2]), f1 = (real3)(F[3], F[4], F[5]),
              f2 = (real3)(F[6], F[7], F[8]);
  const real3 b1 = (real3)(dot(f0, v1), dot(f1, v1), dot(f2, v1));
  const real3 b2 = (real3)(dot(f0, v2), dot(f1, v2), dot(f2, v2));
  const real n1 = norm3(b1);
  const real3 u1 = n1 > 0 ? b1 / n1 : (real3)(1, 0, 0);
  // Gram-Schmidt twice keeps u2 orthogonal to u1 when b2 is much shorter than b1.
  real3 w = b2 - dot(u1, b2) * u1;
  w -= dot(u1, w) * u1;
  const real n2 = norm3(w);
  const real3 u2 = n2 > REAL_EPSILON * n1 ? w / n2 : anyOrthogonal(u1);
  const real3 u3 = cross(u1, u2);
  // R = U V^T = u1 v1^T + u2 v2^T + u3 v3^T.
  sumOfOuterProducts(u1, v1, u2, v2, u3, v3, R);
}

/// Nearest proper rotation r of the 3 x 3 m, both row-major (or both column-major: the nearest
/// rotation of M^T is R^T): Newton's polar factor when det m > 0, else rotationByEigen. The same
/// steps as projections::nearestRotation of the CPU reference.
inline void nearestRotation(const real* m, real* r) {
  if (!polarByNewton(m, r)) rotationByEigen(m, r);
}
