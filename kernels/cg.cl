// Jacobi-preconditioned conjugate gradients on K x = b, K = c M + L, for the three columns of
// an `n by 3` (column-major) x and b at once (GlobalSolve::ConjugateGradient; host side in
// host/opencl/device_solver.cpp). L is the scalar `n by n` CSR (row_start, column, value) shared
// by the columns; the Jacobi preconditioner is 1/diag(K), recomputed by cg_start for each c.
//
// One CG iteration is two launches and no host wait:
//   cg_direction  beta = (r.z)_new/(r.z)_old, p = z + beta p_old, q = K p and the partials of p.q;
//   cg_update     alpha = (r.z)/(p.q), x += alpha p, r -= alpha q, z = r/diag(K) and the partials
//                 of r.z, r.r.
// x and b are state slots (column-major); the CG's own vectors r, z, p, q are stored row by row
// (x, y, z of a particle together, vload3), so that the SpMV's gather of a neighbour's z and p
// touches one cache line instead of six.
// Every scalar is a sum of per-group partials (groupSums below), which the
// next kernel adds itself in group order in every work-group: the same order everywhere, so every
// group uses the same alpha and beta and nothing is read back. Each work-item serves the rows
// i = global id, + global size, ... (the group count is fixed by n, so are the sums' orders).
// Partials of a quantity with three columns lie at [column * groups + group].

// The three column sums of `partials` (3 * groups), computed by work-items 0..2 into out[0..2]
// and visible to the whole group after the barrier.
inline void columnSums(__global const real* partials, int groups, __local real* out) {
  const int lid = get_local_id(0);
  if (lid < 3) {
    real sum = 0;
    for (int g = 0; g < groups; ++g) sum += partials[lid * groups + g];
    out[lid] = sum;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
}

// The group sums of `count` values per work-item (v[0..count)), one tree in local memory for all
// of them (a barrier per level, not per value), left in scratch[k * local size] for value k.
// `scratch` holds CG_GROUP_SUMS * local size reals (the prelude's; the host sizes it), so
// count <= CG_GROUP_SUMS. The tree is workGroupSum's: a fixed order.
inline void groupSums(const real* v, int count, __local real* scratch) {
  const int lid = get_local_id(0), size = get_local_size(0);
  for (int k = 0; k < count; ++k) scratch[k * size + lid] = v[k];
  barrier(CLK_LOCAL_MEM_FENCE);
  for (int stride = size / 2; stride > 0; stride >>= 1) {
    if (lid < stride)
      for (int k = 0; k < count; ++k) scratch[k * size + lid] += scratch[k * size + lid + stride];
    barrier(CLK_LOCAL_MEM_FENCE);
  }
}

// Work-items 0..2 store the sums of values first..first+2 (three columns) as the group's partials.
inline void storePartials3(__local const real* scratch, int first, __global real* partials, int groups) {
  const int lid = get_local_id(0);
  if (lid < 3) partials[lid * groups + get_group_id(0)] = scratch[(first + lid) * get_local_size(0)];
}

inline real3 ratio3(real3 num, real3 den) {
  // A column that has converged exactly (den = 0) stays where it is instead of becoming NaN.
  return (real3)(den.x != 0 ? num.x / den.x : 0, den.y != 0 ? num.y / den.y : 0, den.z != 0 ? num.z / den.z : 0);
}

// r = b - K x, dinv = 1/diag(K), and the partials of r.z, r.r and b.b.
__kernel void cg_start(const int n, const real c, __global const int* row_start, __global const int* column,
                       __global const real* value, __global const real* masses, __global const real* b,
                       __global const real* x, __global real* r, __global real* z, __global real* dinv,
                       __global real* rz_partials,
                       __global real* rr_partials, __global real* bb_partials, __local real* scratch) {
  const int groups = get_num_groups(0);
  real3 rz = (real3)(0), rr = (real3)(0), bb = (real3)(0);
  for (int i = get_global_id(0); i < n; i += get_global_size(0)) {
    real diagonal = c * masses[i];
    real3 kx = diagonal * loadRow(x, n, i);
    for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
      const int j = column[k];
      kx += value[k] * loadRow(x, n, j);
      if (j == i) diagonal += value[k];
    }
    const real3 bi = loadRow(b, n, i);
    const real3 ri = bi - kx;
    const real d = 1 / diagonal;
    vstore3(ri, i, r);
    vstore3(d * ri, i, z);
    dinv[i] = d;
    rz += d * ri * ri;
    rr += ri * ri;
    bb += bi * bi;
  }
  const real v[CG_GROUP_SUMS] = {rz.x, rz.y, rz.z, rr.x, rr.y, rr.z, bb.x, bb.y, bb.z};
  groupSums(v, CG_GROUP_SUMS, scratch);
  storePartials3(scratch, 0, rz_partials, groups);
  storePartials3(scratch, 3, rr_partials, groups);
  storePartials3(scratch, 6, bb_partials, groups);
}

// p = z + beta p_old (beta = 0 on the first iteration), q = K p, partials of p.q.
__kernel void cg_direction(const int n, const real c, __global const int* row_start, __global const int* column,
                           __global const real* value, __global const real* masses, __global const real* z,
                           __global const real* p_old, __global real* p,
                           __global real* q, __global const real* rz_partials, __global const real* rz_old_partials,
                           const int first, __global real* pq_partials, __local real* scratch) {
  const int groups = get_num_groups(0);
  __local real rz[3], rz_old[3];
  columnSums(rz_partials, groups, rz);
  columnSums(rz_old_partials, groups, rz_old);
  const real3 beta = first ? (real3)(0) : ratio3((real3)(rz[0], rz[1], rz[2]), (real3)(rz_old[0], rz_old[1], rz_old[2]));
  real3 pq = (real3)(0);
  for (int i = get_global_id(0); i < n; i += get_global_size(0)) {
    real3 qi = (real3)(0);
    // The first direction reads no p_old (whatever a previous solve left there).
    for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
      const int j = column[k];
      real3 pj = vload3(j, z);
      if (!first) pj += beta * vload3(j, p_old);
      qi += value[k] * pj;
    }
    real3 pi = vload3(i, z);
    if (!first) pi += beta * vload3(i, p_old);
    qi += c * masses[i] * pi;
    vstore3(pi, i, p);
    vstore3(qi, i, q);
    pq += pi * qi;
  }
  const real v[3] = {pq.x, pq.y, pq.z};
  groupSums(v, 3, scratch);
  storePartials3(scratch, 0, pq_partials, groups);
}

// alpha = (r.z)/(p.q), x += alpha p, r -= alpha q, z = r/diag(K), partials of the new r.z and r.r.
__kernel void cg_update(const int n, __global const real* dinv, __global const real* p, __global const real* q,
                        __global real* x, __global real* r, __global real* z, __global const real* rz_partials,
                        __global const real* pq_partials, __global real* rz_new_partials,
                        __global real* rr_partials, __local real* scratch) {
  const int groups = get_num_groups(0);
  __local real rz[3], pq[3];
  columnSums(rz_partials, groups, rz);
  columnSums(pq_partials, groups, pq);
  const real3 alpha = ratio3((real3)(rz[0], rz[1], rz[2]), (real3)(pq[0], pq[1], pq[2]));
  real3 rz_new = (real3)(0), rr = (real3)(0);
  for (int i = get_global_id(0); i < n; i += get_global_size(0)) {
    const real3 xi = loadRow(x, n, i) + alpha * vload3(i, p);
    const real3 ri = vload3(i, r) - alpha * vload3(i, q);
    const real3 zi = dinv[i] * ri;
    x[i] = xi.x, x[n + i] = xi.y, x[2 * n + i] = xi.z;
    vstore3(ri, i, r);
    vstore3(zi, i, z);
    rz_new += zi * ri;
    rr += ri * ri;
  }
  const real v[6] = {rz_new.x, rz_new.y, rz_new.z, rr.x, rr.y, rr.z};
  groupSums(v, 6, scratch);
  storePartials3(scratch, 0, rz_new_partials, groups);
  storePartials3(scratch, 3, rr_partials, groups);
}
