// Pins: A_e x = x_j, weight k, projection q(t) (the target; uploaded by the host per time).
// Contribution p relative to the pin base. Scalar components, as in springs.cl.

/// E = k/2 |x - q|^2
inline real pinEnergy(real rx, real ry, real rz, real k) {
  return (real)0.5 * k * (rx * rx + ry * ry + rz * rz);
}

// targets: #pins by 3, column-major.
__kernel void pin_contributions(__global const real* x, const int n, const int count,
                                __global const int* vertex, __global const real* stiffness,
                                __global const real* targets, const int base, const int mode,
                                __global real* contrib) {
  const int p = get_global_id(0);
  if (p < count) {
    const int j = vertex[p];
    const real k = stiffness[p];
    real qx = targets[p], qy = targets[count + p], qz = targets[2 * count + p];
    if (mode == MODE_FORCE) {  // k (q - x)
      qx -= x[j];
      qy -= x[n + j];
      qz -= x[2 * n + j];
    }
    __global real* c = contrib + 3 * (base + p);
    c[0] = k * qx;
    c[1] = k * qy;
    c[2] = k * qz;
  }
}

/// Energy of pin p (of `count`) at the positions x (summed by potential_partials in energy.cl).
inline real pinEnergyAt(__global const real* x, int n, int count, __global const int* vertex,
                        __global const real* stiffness, __global const real* targets, int p) {
  const int j = vertex[p];
  return pinEnergy(x[j] - targets[p], x[n + j] - targets[count + p],
                   x[2 * n + j] - targets[2 * count + p], stiffness[p]);
}
