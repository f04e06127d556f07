// Tet strain: A x = F^T (F = Ds Dm^-1), params (k V): p = R^T with R the nearest rotation of F.
inline real tet_project(const real* ax, __global const real* params, real* p) {
  real F[9], R[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) F[3 * i + j] = ax[3 * j + i];
  nearestRotation(F, R);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) p[3 * i + j] = R[3 * j + i];
  return halfWeightedSquaredDistance(params[0], ax, p, 9);
}
