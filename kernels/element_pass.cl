// The generic element of the element pass, instantiated once per element type by the host
// (host/opencl/element_program.cpp) with
//   ELEMENT(f)        the type's identifier pasted to f (spring_ ## f),
//   EL_VERTICES       K, the vertex tuple size,
//   EL_ROWS           R, the rows of A_e (A_e x is R by 3),
//   EL_PARAMS         P, reals per element in params (weight first),
//   EL_SHARED_COEFFICIENTS  {A_e} as an initializer when every element of the type shares
//                     one A_e (literals: multiplying by a constant 1 or -1 costs nothing).
// The type's own file defines ELEMENT(project)(ax, params, p): p = projection of A_e x, returning
// the element's energy w_e/2 ||A_e x - p_e||^2 (in whatever form is most accurate for the type).
// The loops have compile-time bounds and are unrolled completely (#pragma unroll), so ax and p
// live in registers and PoCL's vectorizer sees the work-item loop as the innermost one.

/// Element e: A_e x, its projection p_e, the contributions of `flags` written at
/// base + K e + k, and the energy w_e/2 ||A_e x - p_e||^2 (0 unless PASS_ENERGY or
/// PASS_ENERGY_PER_ELEMENT).
inline real ELEMENT(element)(__global const real* x, const int n, const int e, const int flags,
                             const int base, __global const int* vertices,
                             __global const real* coefficients, __global const real* params,
                             __global real* contrib) {
  __global const int* v = vertices + EL_VERTICES * e;
#ifdef EL_SHARED_COEFFICIENTS
  const real a[EL_ROWS * EL_VERTICES] = EL_SHARED_COEFFICIENTS;
#else
  __global const real* a = coefficients + EL_ROWS * EL_VERTICES * e;
#endif
  __global const real* prm = params + EL_PARAMS * e;
  // Sums start from their first term, not from 0 (0 + x cannot be folded to x): with the shared
  // coefficients +-1 of springs and pins A_e x is then exactly x_a - x_b or x_j.
  real ax[3 * EL_ROWS];
#pragma unroll
  for (int k = 0; k < EL_VERTICES; ++k) {
    const int j = v[k];
    const real x0 = x[j], x1 = x[n + j], x2 = x[2 * n + j];
#pragma unroll
    for (int r = 0; r < EL_ROWS; ++r) {
      const real c = a[EL_VERTICES * r + k];
      ax[3 * r] = k == 0 ? c * x0 : ax[3 * r] + c * x0;
      ax[3 * r + 1] = k == 0 ? c * x1 : ax[3 * r + 1] + c * x1;
      ax[3 * r + 2] = k == 0 ? c * x2 : ax[3 * r + 2] + c * x2;
    }
  }
  real p[3 * EL_ROWS];
  const real energy = ELEMENT(project)(ax, prm, p);
  if (flags & (PASS_PROJECTION | PASS_FORCE)) {
    const real w = prm[0];
    const bool force = (flags & PASS_FORCE) != 0;
#pragma unroll
    for (int i = 0; i < 3 * EL_ROWS; ++i) p[i] = w * (force ? p[i] - ax[i] : p[i]);
#pragma unroll
    for (int k = 0; k < EL_VERTICES; ++k) {
      real c0 = a[k] * p[0], c1 = a[k] * p[1], c2 = a[k] * p[2];
#pragma unroll
      for (int r = 1; r < EL_ROWS; ++r) {
        const real c = a[EL_VERTICES * r + k];
        c0 += c * p[3 * r];
        c1 += c * p[3 * r + 1];
        c2 += c * p[3 * r + 2];
      }
      __global real* out = contrib + 3 * (base + EL_VERTICES * e + k);
      out[0] = c0;
      out[1] = c1;
      out[2] = c2;
    }
  }
  return (flags & (PASS_ENERGY | PASS_ENERGY_PER_ELEMENT)) ? energy : (real)0;
}
