// Pins: A_e x = x_j, weight k, projection q(t) (the target; uploaded by the host per time).
// Contribution p relative to the pin base.

/// E = k/2 |x - q|^2
inline real pinEnergy(real3 x, real3 q, real k) {
  const real3 r = x - q;
  return (real)0.5 * k * dot(r, r);
}

__kernel void pin_contributions(__global const real* x, const int n, const int count,
                                __global const int* vertex, __global const real* stiffness,
                                __global const real* targets, const int base, const int mode,
                                __global real* contrib) {
  const int p = get_global_id(0);
  if (p >= count) return;
  const real3 q = loadRow(targets, count, p);
  const real3 c = stiffness[p] * (mode == MODE_FORCE ? q - loadRow(x, n, vertex[p]) : q);
  vstore3(c, base + p, contrib);
}

__kernel void pin_energies(__global const real* x, const int n, const int count,
                           __global const int* vertex, __global const real* stiffness,
                           __global const real* targets, __global real* energies,
                           const int offset) {
  const int p = get_global_id(0);
  if (p >= count) return;
  energies[offset + p] = pinEnergy(loadRow(x, n, vertex[p]), loadRow(targets, count, p), stiffness[p]);
}
