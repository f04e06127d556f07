// Per-vertex gather over the contribution CSR: each vertex sums the contributions listed for it
// in list order, so the result does not depend on scheduling (no atomics).

inline real3 sumContributions(__global const int* offsets, __global const int* list,
                              __global const real* contrib, int j) {
  real3 s = (real3)(0, 0, 0);
  const int end = offsets[j + 1];
  for (int k = offsets[j]; k < end; ++k) s += vload3(list[k], contrib);
  return s;
}

/// rhs_j = c m_j y_j + f_ext_j + sum_e (w_e A_e^T p_e)_j
__kernel void gather_rhs(const int n, __global const int* offsets, __global const int* list,
                         __global const real* contrib, __global const real* masses,
                         __global const real* fext, __global const real* y, const real c,
                         __global real* rhs) {
  const int j = get_global_id(0);
  if (j >= n) return;
  const real3 s = sumContributions(offsets, list, contrib, j);
  storeRow(rhs, n, j, (c * masses[j]) * loadRow(y, n, j) + loadRow(fext, n, j) + s);
}

/// a_j = (f_ext_j + sum_e (w_e A_e^T (p_e - A_e x))_j) / m_j
__kernel void gather_accelerations(const int n, __global const int* offsets,
                                   __global const int* list, __global const real* contrib,
                                   __global const real* masses, __global const real* fext,
                                   __global real* dst) {
  const int j = get_global_id(0);
  if (j >= n) return;
  const real3 s = sumContributions(offsets, list, contrib, j);
  storeRow(dst, n, j, (loadRow(fext, n, j) + s) / masses[j]);
}
