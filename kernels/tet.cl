// Tet strain: A x = F^T (F = Ds Dm^-1), params (k V): p = R^T with R the nearest rotation of F,
// which is the nearest rotation of F^T transposed: ax goes in as it is stored.
inline real tet_project(const real* ax, __global const real* params, real* p) {
  nearestRotation(ax, p);
  return halfWeightedSquaredDistance(params[0], ax, p, 9);
}
