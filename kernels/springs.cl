// Springs: A_e x = d = x_a - x_b, weight k, projection onto |d| = r.
// Contributions 2s (end a, +) and 2s+1 (end b, -) relative to the spring base.
// The math is written on scalar components (no real3 values, no branches): PoCL then
// vectorizes the work-item loop, which it does not do for 3-vectors.

/// p = r d/|d|. Coincident endpoints (|d| < 1e-12 max(r, 1)) project along the rest direction
/// (rx, ry, rz) (unit vector from b to a at rest, +x when that is undefined too).
inline void springProjection(real dx, real dy, real dz, real rest, real rx, real ry, real rz,
                             real* px, real* py, real* pz) {
  const real len = sqrt(dx * dx + dy * dy + dz * dz);
  const bool degenerate = len < (real)1e-12 * fmax(rest, (real)1);
  const real scale = degenerate ? (real)0 : rest / len;
  *px = degenerate ? rest * rx : scale * dx;
  *py = degenerate ? rest * ry : scale * dy;
  *pz = degenerate ? rest * rz : scale * dz;
}

/// E = k/2 (|d| - r)^2
inline real springEnergy(real dx, real dy, real dz, real rest, real k) {
  const real stretch = sqrt(dx * dx + dy * dy + dz * dz) - rest;
  return (real)0.5 * k * stretch * stretch;
}

// params: 5 reals per spring: rest length, stiffness, rest direction (x, y, z).
__kernel void spring_contributions(__global const real* x, const int n, const int count,
                                   __global const int* ends, __global const real* params,
                                   const int base, const int mode, __global real* contrib) {
  const int s = get_global_id(0);
  if (s < count) {
    const int a = ends[2 * s], b = ends[2 * s + 1];
    const real dx = x[a] - x[b], dy = x[n + a] - x[n + b], dz = x[2 * n + a] - x[2 * n + b];
    __global const real* q = params + 5 * s;
    const real k = q[1];
    real px, py, pz;
    springProjection(dx, dy, dz, q[0], q[2], q[3], q[4], &px, &py, &pz);
    if (mode == MODE_FORCE) {
      px -= dx;
      py -= dy;
      pz -= dz;
    }
    __global real* c = contrib + 3 * (base + 2 * s);
    c[0] = k * px;
    c[1] = k * py;
    c[2] = k * pz;
    c[3] = -(k * px);
    c[4] = -(k * py);
    c[5] = -(k * pz);
  }
}

/// Energy of spring s at the positions x (summed by potential_partials in energy.cl).
inline real springEnergyAt(__global const real* x, int n, __global const int* ends,
                           __global const real* params, int s) {
  const int a = ends[2 * s], b = ends[2 * s + 1];
  const real dx = x[a] - x[b], dy = x[n + a] - x[n + b], dz = x[2 * n + a] - x[2 * n + b];
  return springEnergy(dx, dy, dz, params[5 * s], params[5 * s + 1]);
}
