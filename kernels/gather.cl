// Per-vertex gather over the contribution CSR: each vertex sums the contributions listed for it
// in list order, so the result does not depend on scheduling (no atomics).

// Scalar accumulators (no real3 values): PoCL compiles them to tighter loops.
#define SUM_CONTRIBUTIONS(j, sx, sy, sz)                  \
  real sx = 0, sy = 0, sz = 0;                            \
  {                                                       \
    const int end_ = offsets[(j) + 1];                    \
    for (int k_ = offsets[j]; k_ < end_; ++k_) {          \
      __global const real* c_ = contrib + 3 * list[k_];   \
      sx += c_[0];                                        \
      sy += c_[1];                                        \
      sz += c_[2];                                        \
    }                                                     \
  }

/// rhs_j = c m_j y_j + f_ext_j + sum_e (w_e A_e^T p_e)_j
__kernel void gather_rhs(const int n, __global const int* offsets, __global const int* list,
                         __global const real* contrib, __global const real* masses,
                         __global const real* fext, __global const real* y, const real c,
                         __global real* rhs) {
  const int j = get_global_id(0);
  if (j < n) {
    SUM_CONTRIBUTIONS(j, sx, sy, sz)
    const real cm = c * masses[j];
    rhs[j] = cm * y[j] + fext[j] + sx;
    rhs[n + j] = cm * y[n + j] + fext[n + j] + sy;
    rhs[2 * n + j] = cm * y[2 * n + j] + fext[2 * n + j] + sz;
  }
}

/// g_j = c m_j (x_j - y_j) - f_ext_j - sum_e (w_e A_e^T (p_e - A_e x))_j: the gradient of the
/// solve's objective, from the force form of the element pass
__kernel void gather_gradient(const int n, __global const int* offsets, __global const int* list,
                              __global const real* contrib, __global const real* masses,
                              __global const real* fext, __global const real* x,
                              __global const real* y, const real c, __global real* gradient) {
  const int j = get_global_id(0);
  if (j < n) {
    SUM_CONTRIBUTIONS(j, sx, sy, sz)
    const real cm = c * masses[j];
    gradient[j] = cm * (x[j] - y[j]) - fext[j] - sx;
    gradient[n + j] = cm * (x[n + j] - y[n + j]) - fext[n + j] - sy;
    gradient[2 * n + j] = cm * (x[2 * n + j] - y[2 * n + j]) - fext[2 * n + j] - sz;
  }
}

/// a_j = (f_ext_j + sum_e (w_e A_e^T (p_e - A_e x))_j) / m_j
__kernel void gather_accelerations(const int n, __global const int* offsets,
                                   __global const int* list, __global const real* contrib,
                                   __global const real* masses, __global const real* fext,
                                   __global real* dst) {
  const int j = get_global_id(0);
  if (j < n) {
    SUM_CONTRIBUTIONS(j, sx, sy, sz)
    const real m = masses[j];
    dst[j] = (fext[j] + sx) / m;
    dst[n + j] = (fext[n + j] + sy) / m;
    dst[2 * n + j] = (fext[2 * n + j] + sz) / m;
  }
}
