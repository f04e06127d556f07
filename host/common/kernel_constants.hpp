#pragma once
// The constants the host and the kernels must agree on, declared once. Each entry of the lists
// below,
//   X(KERNEL_NAME, host, value)
// gives the kernels `#define KERNEL_NAME value` in the prelude (kernelPrelude()) that
// ocl::buildProgram puts before the source of every program it compiles, and the host its value
// under the name `host`: a constexpr or enumerator declared here, or, for the collider shapes, the
// public ColliderShape enumerator the code must equal (static_asserts in elements/contact.hpp).
// No kernel file defines these names and no host file writes their values again
// (tests/test_kernel_prelude.cpp and test_opencl_kernel_prelude.cpp check both sides).
//
// Integers go into the prelude as decimal numbers. Reals go in as `((real)value)` with the literal
// exactly as written here, so a float program rounds the same decimal text the kernels wrote
// before (and a double program reads the host's double bit for bit).
//
// Leaf header: no OpenCL, Eigen or scene types, so the element math, the CPU reference and the
// CPU-only build include it as well.
#include <string>

// ---- What an element pass computes, bit flags (kernels/element_pass.cl, the dispatcher of
// host/opencl/element_program.cpp, both backends):
//   projection: per contribution w_e A_e^T p_e, the local step's share of the global rhs
//   force: per contribution w_e A_e^T (p_e - A_e x) = -grad E_e
//   energy: per work-group (CPU: per pass) the summed energies w_e/2 ||A_e x - p_e||^2
//   energy per element: each element's energy on its own, OpenCL only (the per-scene sums of a
//     batch, kernels/segments.cl: a group's sum would mix scenes; the CPU reference sums a
//     scene's elements with passRange instead)
#define STABINT_PASS_FLAGS(X)            \
  X(PASS_PROJECTION, kPassProjection, 1) \
  X(PASS_FORCE, kPassForce, 2)           \
  X(PASS_ENERGY, kPassEnergy, 4)         \
  X(PASS_ENERGY_PER_ELEMENT, kPassEnergyPerElement, 8)

// ---- Collider shape codes: the shape entry of a collider's geometry (below) holds
// static_cast<int>(ColliderShape) (include/stabint/scene.hpp).
#define STABINT_COLLIDER_SHAPES(X)             \
  X(COLLIDER_PLANE, ColliderShape::Plane, 0)   \
  X(COLLIDER_SPHERE, ColliderShape::Sphere, 1) \
  X(COLLIDER_BOX, ColliderShape::Box, 2)       \
  X(COLLIDER_CAPSULE, ColliderShape::Capsule, 3)

// ---- A collider at time t as COLLIDER_GEOMETRY reals (host/elements/contact.hpp,
// kernels/contact.cl):
//   shape, center (3), a (3), radius
// with `a` the unit normal of a plane, the half extents of a box, the other end of a capsule's
// axis (unused by spheres). A contact element's params are its weight w_j, then the geometry at
// CONTACT_GEOMETRY.
#define STABINT_CONTACT_LAYOUT(X)            \
  X(GEOMETRY_SHAPE, kGeometryShape, 0)       \
  X(GEOMETRY_CENTER, kGeometryCenter, 1)     \
  X(GEOMETRY_A, kGeometryA, 4)               \
  X(GEOMETRY_RADIUS, kGeometryRadius, 7)     \
  X(COLLIDER_GEOMETRY, kColliderGeometry, 8) \
  X(CONTACT_GEOMETRY, kContactGeometry, 1)

// ---- The per-scene sums of a batch (kernels/segments.cl, the OpenCL backend's segment table):
// a row of the segment table is SEGMENT_ROW_HEAD ints (the scene's first particle and particle
// count), then SEGMENT_ROW_PER_BLOCK ints per element block (the first index of its elements'
// energies and their count); segment_energies writes SEGMENT_ENERGIES sums per scene, the
// internal, pin and external energies at these offsets.
#define STABINT_SEGMENT_LAYOUT(X)                  \
  X(SEGMENT_ROW_HEAD, kSegmentRowHead, 2)          \
  X(SEGMENT_ROW_PER_BLOCK, kSegmentRowPerBlock, 2) \
  X(SEGMENT_ENERGIES, kSegmentEnergies, 3)         \
  X(SEGMENT_INTERNAL, kSegmentInternal, 0)         \
  X(SEGMENT_PINS, kSegmentPins, 1)                 \
  X(SEGMENT_EXTERNAL, kSegmentExternal, 2)

// ---- The device CG (kernels/cg.cl, host/opencl/device_solver.cpp): the most values one
// groupSums call reduces (cg_start's r.z, r.r and b.b, three columns each); the local scratch
// holds this many reals per work-item.
#define STABINT_CG_LAYOUT(X) X(CG_GROUP_SUMS, kCgGroupSums, 9)

// ---- The nearest rotation (host/elements/projections.cpp, kernels/projections.cl) and the
// projection onto a sphere (projections.hpp's ontoSphere, projections.cl's):
//   Newton's polar iteration stops after MAX_NEWTON_ITERATIONS (never reached in practice); the
//   Jacobi eigen-decomposition after MAX_JACOBI_SWEEPS.
#define STABINT_PROJECTION_INTS(X)                   \
  X(MAX_NEWTON_ITERATIONS, kMaxNewtonIterations, 16) \
  X(MAX_JACOBI_SWEEPS, kMaxJacobiSweeps, 20)
//   FLAT_VOLUME: Newton needs det M > 0; below this fraction of ||M||_F^3 (a cube of the same
//     size has 3^-3/2 = 0.19) M counts as flat and takes the eigen-decomposition instead;
//   NEWTON_SCALING: Higham's scaling stays on while an update's squared size exceeds this;
//   DEGENERATE_LENGTH: ontoSphere's v with |v| below this times max(r, 1) has no direction of its
//     own and projects along the element's fallback direction.
#define STABINT_PROJECTION_REALS(X)       \
  X(FLAT_VOLUME, kFlatVolume, 1e-6)       \
  X(NEWTON_SCALING, kNewtonScaling, 1e-4) \
  X(DEGENERATE_LENGTH, kDegenerateLength, 1e-12)

// ---- Every entry, for the prelude and the tests.
#define STABINT_KERNEL_INTS(X) \
  STABINT_PASS_FLAGS(X)        \
  STABINT_COLLIDER_SHAPES(X)   \
  STABINT_CONTACT_LAYOUT(X)    \
  STABINT_SEGMENT_LAYOUT(X)    \
  STABINT_CG_LAYOUT(X)         \
  STABINT_PROJECTION_INTS(X)
#define STABINT_KERNEL_REALS(X) STABINT_PROJECTION_REALS(X)

namespace stabint {

#define STABINT_KERNEL_ENUMERATOR(kernel_name, host, value) host = value,
#define STABINT_KERNEL_INT(kernel_name, host, value) inline constexpr int host = value;
#define STABINT_KERNEL_REAL(kernel_name, host, value) inline constexpr double host = value;

/// What an element pass computes, as bit flags (STABINT_PASS_FLAGS above).
enum PassFlags : int { STABINT_PASS_FLAGS(STABINT_KERNEL_ENUMERATOR) };

STABINT_CONTACT_LAYOUT(STABINT_KERNEL_INT)
STABINT_SEGMENT_LAYOUT(STABINT_KERNEL_INT)
STABINT_CG_LAYOUT(STABINT_KERNEL_INT)
STABINT_PROJECTION_INTS(STABINT_KERNEL_INT)
STABINT_PROJECTION_REALS(STABINT_KERNEL_REAL)

#undef STABINT_KERNEL_ENUMERATOR
#undef STABINT_KERNEL_INT
#undef STABINT_KERNEL_REAL

static_assert(kGeometryShape == 0 && kGeometryCenter + 3 <= kGeometryA && kGeometryA + 3 <= kGeometryRadius &&
                  kGeometryRadius + 1 == kColliderGeometry,
              "the collider geometry's entries overlap or leave gaps");
static_assert(kContactGeometry >= 1, "a contact element's params start with its weight");
static_assert(kSegmentInternal < kSegmentEnergies && kSegmentPins < kSegmentEnergies &&
                  kSegmentExternal < kSegmentEnergies,
              "the per-scene energies lie within a scene's sums");

/// `#define KERNEL_NAME value` for every entry of STABINT_KERNEL_INTS and STABINT_KERNEL_REALS,
/// one per line: the prelude of every OpenCL program (ocl::buildProgram prepends it).
const std::string& kernelPrelude();

}  // namespace stabint
