// Spring: A x = d = x_a - x_b, params (k, r, rest direction): p = r d/|d|, E = k/2 (|d| - r)^2.
inline real spring_project(const real* ax, __global const real* params, real* p) {
  const real stretch = ontoSphere(ax, params[1], params + 2, p) - params[1];
  return (real)0.5 * params[0] * stretch * stretch;
}
