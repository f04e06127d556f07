// Springs: A_e x = d = x_a - x_b, weight k, projection onto |d| = r.
// Contributions 2s (end a, +) and 2s+1 (end b, -) relative to the spring base.

/// p = r d/|d|. Coincident endpoints (|d| < 1e-12 max(r, 1)) project along the rest direction
/// `rest_dir` (unit vector from b to a at rest, +x when that is undefined too).
inline real3 springProjection(real3 d, real rest, real3 rest_dir) {
  const real len = norm3(d);
  if (len < (real)1e-12 * fmax(rest, (real)1)) return rest * rest_dir;
  return rest * (d / len);
}

/// E = k/2 (|d| - r)^2
inline real springEnergy(real3 d, real rest, real k) {
  const real stretch = norm3(d) - rest;
  return (real)0.5 * k * stretch * stretch;
}

// params: 5 reals per spring: rest length, stiffness, rest direction (x, y, z).
__kernel void spring_contributions(__global const real* x, const int n, const int count,
                                   __global const int2* ends, __global const real* params,
                                   const int base, const int mode, __global real* contrib) {
  const int s = get_global_id(0);
  if (s >= count) return;
  const int2 ab = ends[s];
  const real3 d = loadRow(x, n, ab.x) - loadRow(x, n, ab.y);
  __global const real* q = params + 5 * s;
  const real3 p = springProjection(d, q[0], (real3)(q[2], q[3], q[4]));
  const real3 c = q[1] * (mode == MODE_FORCE ? p - d : p);
  vstore3(c, base + 2 * s, contrib);
  vstore3(-c, base + 2 * s + 1, contrib);
}

__kernel void spring_energies(__global const real* x, const int n, const int count,
                              __global const int2* ends, __global const real* params,
                              __global real* energies, const int offset) {
  const int s = get_global_id(0);
  if (s >= count) return;
  const int2 ab = ends[s];
  const real3 d = loadRow(x, n, ab.x) - loadRow(x, n, ab.y);
  energies[offset + s] = springEnergy(d, params[5 * s], params[5 * s + 1]);
}
