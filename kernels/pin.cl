// Pin: A x = x_j, params (k, q(t)): p = q(t), uploaded by the host whenever t changes.
inline real pin_project(const real* ax, __global const real* params, real* p) {
  p[0] = params[1];
  p[1] = params[2];
  p[2] = params[3];
  return halfWeightedSquaredDistance(params[0], ax, p, 3);
}
