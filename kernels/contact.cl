// Contact: A x = x_j, params (w_j, then the collider's geometry at CONTACT_GEOMETRY: shape,
// center (3), a (3), radius at the GEOMETRY_* offsets, the prelude's), the collider at time t
// uploaded by the host whenever t changes (host/elements/contact.hpp has the layout and the C++
// twin, closestPointOutside). p = the closest point of the collider's outside, x_j itself out of
// contact. Shape codes are the prelude's COLLIDER_* (the ColliderShape values).
inline real contact_project(const real* ax, __global const real* params, real* p) {
  p[0] = ax[0];
  p[1] = ax[1];
  p[2] = ax[2];
  // Out of the contact set (weight 0) the element does nothing: skip the geometry.
  if (params[0] == (real)0) return (real)0;
  __global const real* g = params + CONTACT_GEOMETRY;
  const int shape = (int)g[GEOMETRY_SHAPE];
  const real c0 = g[GEOMETRY_CENTER], c1 = g[GEOMETRY_CENTER + 1], c2 = g[GEOMETRY_CENTER + 2];
  const real a0 = g[GEOMETRY_A], a1 = g[GEOMETRY_A + 1], a2 = g[GEOMETRY_A + 2];
  const real radius = g[GEOMETRY_RADIUS];
  if (shape == COLLIDER_PLANE) {
    const real d = (ax[0] - c0) * a0 + (ax[1] - c1) * a1 + (ax[2] - c2) * a2;
    if (d < (real)0) {
      p[0] = ax[0] - d * a0;
      p[1] = ax[1] - d * a1;
      p[2] = ax[2] - d * a2;
    }
  } else if (shape == COLLIDER_BOX) {
    const real q[3] = {ax[0] - c0, ax[1] - c1, ax[2] - c2};
    const real e[3] = {a0, a1, a2};
    const real c[3] = {c0, c1, c2};
    int axis = -1;
    real depth = 0;
    bool inside = true;
    for (int i = 0; i < 3; ++i) {
      const real di = e[i] - fabs(q[i]);
      if (!(di > (real)0)) inside = false;
      if (axis < 0 || di < depth) {
        axis = i;
        depth = di;
      }
    }
    if (inside) p[axis] = q[axis] < (real)0 ? c[axis] - e[axis] : c[axis] + e[axis];
  } else {  // COLLIDER_SPHERE, or COLLIDER_CAPSULE: the sphere about the closest point of its axis
    real s0 = c0, s1 = c1, s2 = c2;
    if (shape == COLLIDER_CAPSULE) {
      const real ab0 = a0 - c0, ab1 = a1 - c1, ab2 = a2 - c2;
      const real along = (ax[0] - c0) * ab0 + (ax[1] - c1) * ab1 + (ax[2] - c2) * ab2;
      const real length2 = ab0 * ab0 + ab1 * ab1 + ab2 * ab2;
      const real u = length2 > (real)0 ? (along <= (real)0 ? (real)0 : (along >= length2 ? (real)1 : along / length2))
                                       : (real)0;
      s0 += u * ab0;
      s1 += u * ab1;
      s2 += u * ab2;
    }
    const real r0 = ax[0] - s0, r1 = ax[1] - s1, r2 = ax[2] - s2;
    const real l2 = r0 * r0 + r1 * r1 + r2 * r2;
    if (l2 < radius * radius) {
      if (l2 > (real)0) {
        const real scale = radius / sqrt(l2);
        p[0] = s0 + scale * r0;
        p[1] = s1 + scale * r1;
        p[2] = s2 + scale * r2;
      } else {
        p[0] = s0;
        p[1] = s1 + radius;
        p[2] = s2;
      }
    }
  }
  return halfWeightedSquaredDistance(params[0], ax, p, 3);
}
