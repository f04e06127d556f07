// Triangle strain: A x = F^T (F = Ds Dm^-1, 3 by 2), params (k A, s_min, s_max):
// p = P^T with P = U clamp(S, s_min, s_max) V^T for F = U S V^T.
//
// V and S^2 from one Jacobi rotation of the 2 by 2 F^T F = [[a, b], [b, c]] (exact for 2 by 2),
// U from Gram-Schmidt on F V, with u2 any unit vector orthogonal to u1 when F has rank < 2.
inline real triangle_strain_project(const real* ax, __global const real* params, real* p) {
  const real3 f0 = (real3)(ax[0], ax[1], ax[2]), f1 = (real3)(ax[3], ax[4], ax[5]);
  const real a = dot(f0, f0), b = dot(f0, f1), c = dot(f1, f1);
  const real theta = (real)0.5 * atan2(2 * b, a - c);
  const real cs = cos(theta), sn = sin(theta);
  // v1 = (cs, sn) belongs to the larger eigenvalue, v2 = (-sn, cs) to the smaller.
  const real half_sum = (real)0.5 * (a + c);
  const real radius = sqrt((real)0.25 * (a - c) * (a - c) + b * b);
  const real s1 = sqrt(half_sum + radius), s2 = sqrt(fmax(half_sum - radius, (real)0));
  const real3 b1 = cs * f0 + sn * f1, b2 = cs * f1 - sn * f0;  // F v1, F v2
  const real n1 = norm3(b1);
  const real3 u1 = n1 > 0 ? b1 / n1 : (real3)(1, 0, 0);
  real3 w = b2 - dot(u1, b2) * u1;
  w -= dot(u1, w) * u1;
  const real n2 = norm3(w);
  const real3 u2 = n2 > REAL_EPSILON * n1 ? w / n2 : anyOrthogonal(u1);
  const real t1 = clamp(s1, params[1], params[2]), t2 = clamp(s2, params[1], params[2]);
  // Row r of P^T = sum_i t_i v_i[r] u_i.
  const real3 p0 = t1 * cs * u1 - t2 * sn * u2, p1 = t1 * sn * u1 + t2 * cs * u2;
  p[0] = p0.x; p[1] = p0.y; p[2] = p0.z;
  p[3] = p1.x; p[4] = p1.y; p[5] = p1.z;
  return halfWeightedSquaredDistance(params[0], ax, p, 6);
}
