// Whole-array operations on n by 3 slots.

/// dst = a x + b y over `len` reals (dst may alias x or y).
__kernel void combine(const int len, const real a, __global const real* x, const real b,
                      __global const real* y, __global real* dst) {
  const int i = get_global_id(0);
  if (i < len) dst[i] = a * x[i] + b * y[i];
}

/// m_j a_j . b_j (summed by mass_dot_partials in energy.cl).
inline real massDotTerm(int n, __global const real* masses, __global const real* a,
                        __global const real* b, int j) {
  return masses[j] * (a[j] * b[j] + a[n + j] * b[n + j] + a[2 * n + j] * b[2 * n + j]);
}

/// -f_ext_j . x_j: the potential of gravity and force fields (f_ext = m g + f(t)) at vertex j.
inline real externalEnergyAt(int n, __global const real* x, __global const real* fext, int j) {
  return -(fext[j] * x[j] + fext[n + j] * x[n + j] + fext[2 * n + j] * x[2 * n + j]);
}

/// One reduction: sum_j m_j a_j . b_j over the n vertices, one partial per work-group, each
/// work-item adding a fixed strided subset (deterministic; see reduce.cl).
__kernel void mass_dot_partials(const int n, __global const real* masses, __global const real* a,
                                __global const real* b, __global real* partials,
                                __local real* scratch) {
  const int local_size = get_local_size(0);
  const int stride = get_num_groups(0) * local_size;
  real s = 0;
  for (int i = get_group_id(0) * local_size + get_local_id(0); i < n; i += stride)
    s += massDotTerm(n, masses, a, b, i);
  s = workGroupSum(s, scratch);
  if (get_local_id(0) == 0) partials[get_group_id(0)] = s;
}
