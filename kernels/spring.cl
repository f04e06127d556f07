// Spring: A x = d = x_a - x_b, params (k, r, rest direction): p = r d/|d|, E = k/2 (|d| - r)^2.
inline real spring_project(const real* ax, __global const real* params, real* p) {
  return ontoSphere(ax, params, p);
}
