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
// Written with scalar components (no real3 values) so that PoCL can vectorize across
// work-items; the formula is springProjection's.
__kernel void spring_contributions(__global const real* x, const int n, const int count,
                                   __global const int* ends, __global const real* params,
                                   const int base, const int mode, __global real* contrib) {
  const int s = get_global_id(0);
  if (s < count) {
    const int a = ends[2 * s], b = ends[2 * s + 1];
    const real dx = x[a] - x[b], dy = x[n + a] - x[n + b], dz = x[2 * n + a] - x[2 * n + b];
    __global const real* q = params + 5 * s;
    // Unconditional loads and selects (no branches) keep the work-item loop vectorizable.
    const real rest = q[0], k = q[1], rx = q[2], ry = q[3], rz = q[4];
    const real len = sqrt(dx * dx + dy * dy + dz * dz);
    const bool degenerate = len < (real)1e-12 * fmax(rest, (real)1);
    const real scale = degenerate ? (real)0 : rest / len;
    real px = degenerate ? rest * rx : scale * dx;
    real py = degenerate ? rest * ry : scale * dy;
    real pz = degenerate ? rest * rz : scale * dz;
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

__kernel void spring_energies(__global const real* x, const int n, const int count,
                              __global const int2* ends, __global const real* params,
                              __global real* energies, const int offset) {
  const int s = get_global_id(0);
  if (s >= count) return;
  const int2 ab = ends[s];
  const real3 d = loadRow(x, n, ab.x) - loadRow(x, n, ab.y);
  energies[offset + s] = springEnergy(d, params[5 * s], params[5 * s + 1]);
}
