// Bending hinge: A x = K x (cotangent weights of the rest hinge), params (w, |K x_rest|, rest
// direction): K x held at its rest length, as a spring holds x_a - x_b.
inline real bending_hinge_project(const real* ax, __global const real* params, real* p) {
  return ontoSphere(ax, params, p);
}
