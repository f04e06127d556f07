#pragma once
// Collider geometry, in the one form the contact element (host/elements/contact.cpp,
// kernels/contact.cl) and the step's broad phase, friction and final projection (host/contact/)
// share: a collider at time t is kColliderGeometry reals,
//   shape, center (3), a (3), radius
// at the offsets kGeometryShape, kGeometryCenter, kGeometryA and kGeometryRadius
// (host/common/kernel_constants.hpp declares them for both sides), with `a` the unit normal of a plane,
// the half extents of a box, the other end of a capsule's axis (unused by spheres).
// docs/method.md, "Contact", has the rules.
#include "common/kernel_constants.hpp"

#include <stabint/scene.hpp>

#include <cmath>

namespace stabint {

// The shape codes the kernels compare with (COLLIDER_PLANE, ...) are the ColliderShape values.
#define STABINT_SHAPE_CODE_MATCHES(kernel_name, host, value) \
  static_assert(static_cast<int>(host) == (value), #host " must equal the kernels' " #kernel_name);
STABINT_COLLIDER_SHAPES(STABINT_SHAPE_CODE_MATCHES)
#undef STABINT_SHAPE_CODE_MATCHES

/// A range of indices [first, first + count): the particles a collider acts on, the colliders of
/// one scene of a batch.
struct IndexRange {
  int first = 0;
  int count = 0;
  int end() const { return first + count; }
};

/// The particles collider `c` of a validated `scene` acts on (Collider::first_particle and
/// num_particles; every particle of the scene when num_particles is -1).
IndexRange colliderParticles(const Scene& scene, int c);
/// The contact elements (docs/method.md, "Contact") pair each collider with its particles,
/// collider by collider, each over its particles in order: (collider c, particle
/// colliderParticles(c).first + k) is element firstContactElement(scene, c) + k.
int firstContactElement(const Scene& scene, int c);

/// The geometry of `collider` translated so that its reference point (Collider::center) is at
/// `position` (Forcing::colliderPosition says where that is at a time).
void colliderGeometryAt(const Collider& collider, const Eigen::Vector3d& position, double* geometry);

/// Moves geometry `g` by `shift` (its center, and a capsule's other end).
inline void translateGeometry(const Eigen::Vector3d& shift, double* g) {
  const bool capsule = static_cast<int>(g[kGeometryShape]) == static_cast<int>(ColliderShape::Capsule);
  for (int c = 0; c < 3; ++c) {
    g[kGeometryCenter + c] += shift[c];
    if (capsule) g[kGeometryA + c] += shift[c];
  }
}

/// p = the closest point of the collider's outside to x; returns false (and p = x) when x is
/// not inside. Points on the surface are outside. A point at the exact center of a sphere or on
/// a capsule's axis is pushed out along +y; a point equally deep below two faces of a box goes
/// out through the first of them (x before y before z).
inline bool closestPointOutside(const double* g, const double* x, double* p) {
  for (int c = 0; c < 3; ++c) p[c] = x[c];
  const int shape = static_cast<int>(g[kGeometryShape]);
  const double* center = g + kGeometryCenter;
  const double* a = g + kGeometryA;
  const double radius = g[kGeometryRadius];
  if (shape == static_cast<int>(ColliderShape::Plane)) {
    const double d = (x[0] - center[0]) * a[0] + (x[1] - center[1]) * a[1] + (x[2] - center[2]) * a[2];
    if (!(d < 0.0)) return false;
    for (int c = 0; c < 3; ++c) p[c] = x[c] - d * a[c];
    return true;
  }
  if (shape == static_cast<int>(ColliderShape::Box)) {
    int axis = -1;
    double depth = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double q = x[c] - center[c];
      const double dc = a[c] - (q < 0.0 ? -q : q);
      if (!(dc > 0.0)) return false;
      if (axis < 0 || dc < depth) axis = c, depth = dc;
    }
    p[axis] = x[axis] - center[axis] < 0.0 ? center[axis] - a[axis] : center[axis] + a[axis];
    return true;
  }
  // Sphere, or a capsule: the sphere about the closest point of its axis.
  double s[3] = {center[0], center[1], center[2]};
  if (shape == static_cast<int>(ColliderShape::Capsule)) {
    double ab[3], along = 0.0, length2 = 0.0;
    for (int c = 0; c < 3; ++c) {
      ab[c] = a[c] - center[c];
      along += (x[c] - center[c]) * ab[c];
      length2 += ab[c] * ab[c];
    }
    const double u = length2 > 0.0 ? (along <= 0.0 ? 0.0 : (along >= length2 ? 1.0 : along / length2)) : 0.0;
    for (int c = 0; c < 3; ++c) s[c] = center[c] + u * ab[c];
  }
  const double r[3] = {x[0] - s[0], x[1] - s[1], x[2] - s[2]};
  const double l2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
  if (!(l2 < radius * radius)) return false;
  if (l2 > 0.0) {
    const double scale = radius / std::sqrt(l2);
    for (int c = 0; c < 3; ++c) p[c] = s[c] + scale * r[c];
  } else {
    p[0] = s[0], p[1] = s[1] + radius, p[2] = s[2];
  }
  return true;
}

}  // namespace stabint
