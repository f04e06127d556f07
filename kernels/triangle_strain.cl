// Triangle strain: A x = F^T (F = Ds Dm^-1, 3 by 2), params (k A, s_min, s_max):
// p = P^T with P = U clamp(S, s_min, s_max) V^T for F = U S V^T.
//
// The steps of TriangleStrainKind::project (host/elements/triangle_strain.cpp): V from the 2 by 2
// F^T F = [[a, b], [b, c]] in closed form, U and S from Gram-Schmidt on F V (singular values as
// lengths), u2 any unit vector orthogonal to u1 when F has rank < 2.
inline real triangle_strain_project(const real* ax, __global const real* params, real* p) {
  const real3 f0 = (real3)(ax[0], ax[1], ax[2]), f1 = (real3)(ax[3], ax[4], ax[5]);
  const real a = dot(f0, f0), b = dot(f0, f1), c = dot(f1, f1);
  // v1 = (cs, sn), the eigenvector of the larger eigenvalue, from whichever of (l - c, b) and
  // (b, l - a) has no cancellation; (1, 0) for equal eigenvalues.
  const real half_difference = (real)0.5 * (a - c);
  const real r = sqrt(half_difference * half_difference + b * b);
  const real x = half_difference >= 0 ? half_difference + r : b;
  const real y = half_difference >= 0 ? b : r - half_difference;
  const real length = sqrt(x * x + y * y);
  const real cs = length > 0 ? x / length : (real)1, sn = length > 0 ? y / length : (real)0;
  const real3 b1 = cs * f0 + sn * f1, b2 = cs * f1 - sn * f0;  // F v1, F v2 (v2 = (-sn, cs))
  const real s1 = norm3(b1);
  const real3 u1 = s1 > 0 ? b1 / s1 : (real3)(1, 0, 0);
  real3 w = b2 - dot(u1, b2) * u1;
  w -= dot(u1, w) * u1;
  const real s2 = norm3(w);
  const real3 u2 = s2 > REAL_EPSILON * s1 ? w / s2 : anyOrthogonal(u1);
  const real t1 = clamp(s1, params[1], params[2]), t2 = clamp(s2, params[1], params[2]);
  // Row k of P^T = sum_i t_i v_i[k] u_i.
  const real3 p0 = t1 * cs * u1 - t2 * sn * u2, p1 = t1 * sn * u1 + t2 * cs * u2;
  p[0] = p0.x; p[1] = p0.y; p[2] = p0.z;
  p[3] = p1.x; p[4] = p1.y; p[5] = p1.z;
  return halfWeightedSquaredDistance(params[0], ax, p, 6);
}
