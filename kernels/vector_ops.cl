// Whole-array operations on n by 3 slots.

/// dst = a x + b y over `len` reals (dst may alias x or y).
__kernel void combine(const int len, const real a, __global const real* x, const real b,
                      __global const real* y, __global real* dst) {
  const int i = get_global_id(0);
  if (i < len) dst[i] = a * x[i] + b * y[i];
}

/// terms_j = m_j a_j . b_j (summed by reduce_segments).
__kernel void mass_dot_terms(const int n, __global const real* masses, __global const real* a,
                             __global const real* b, __global real* terms, const int offset) {
  const int j = get_global_id(0);
  if (j < n)
    terms[offset + j] = masses[j] * (a[j] * b[j] + a[n + j] * b[n + j] + a[2 * n + j] * b[2 * n + j]);
}

/// terms_j = -f_ext_j . x_j: the potential of gravity and force fields (f_ext = m g + f(t)).
__kernel void external_energies(const int n, __global const real* x, __global const real* fext,
                                __global real* terms, const int offset) {
  const int j = get_global_id(0);
  if (j < n)
    terms[offset + j] = -(fext[j] * x[j] + fext[n + j] * x[n + j] + fext[2 * n + j] * x[2 * n + j]);
}
