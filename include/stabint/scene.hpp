#pragma once
/// @file
/// The scene model: particles, the elements acting on them (springs, tet strain, triangle strain,
/// bending hinges, pins), gravity, time-dependent force fields, per-body damping and the surface
/// triangles. Matrices are `#particles by 3`, one row per particle. docs/elements.md has the
/// energies. Each struct has its field list, `FIELD(name, "doc")` in the struct's order, from which
/// the bindings are generated (stabint/field_list.hpp).
#include <stabint/enum_list.hpp>
#include <stabint/field_list.hpp>

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace stabint {

/// Spring between particles a and b: E = k/2 (|x_a - x_b| - rest_length)^2.
struct Spring {
  int a = 0;                 ///< first particle
  int b = 0;                 ///< second particle
  double rest_length = 0.0;  ///< m, >= 0
  double stiffness = 0.0;    ///< k, N/m
};

/// The fields of Spring, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_SPRING_FIELDS(FIELD) \
  FIELD(a, "first particle")         \
  FIELD(b, "second particle")        \
  FIELD(rest_length, "m, >= 0")      \
  FIELD(stiffness, "k, N/m")
/// @cond
STABINT_FIELD_TABLE_(Spring, STABINT_SPRING_FIELDS, "E = k/2 (|x_a - x_b| - rest_length)^2.")
/// @endcond

/// Co-rotated strain of a tetrahedron: E = k V/2 ||F - R||_F^2 with F = Ds Dm^-1 and R the
/// nearest rotation. The rest shape (Dm, V) is taken from Scene::rest_positions, with
/// Dm = [x1-x0, x2-x0, x3-x0]; the signed rest volume det(Dm)/6 must be positive.
struct Tet {
  std::array<int, 4> vertices{0, 0, 0, 0};  ///< particles x0..x3, positively oriented at rest
  double stiffness = 0.0;                   ///< k, Pa
};

/// The fields of Tet, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_TET_FIELDS(FIELD)                                  \
  FIELD(vertices, "particles x0..x3, positively oriented at rest") \
  FIELD(stiffness, "k, Pa")
/// @cond
STABINT_FIELD_TABLE_(Tet, STABINT_TET_FIELDS, "Co-rotated strain of a tetrahedron against the scene's rest positions.")
/// @endcond

/// Membrane strain of a triangle (Projective Dynamics' strain constraint):
/// E = k A/2 ||F - P||_F^2 with F = Ds Dm^-1 the 3 by 2 deformation gradient against the rest
/// triangle (Ds = [x1-x0, x2-x0], Dm the same rest edges in the rest triangle's own plane), A the
/// rest area and P the nearest 3 by 2 matrix whose singular values lie in
/// [strain_min, strain_max]. The default [1, 1] makes P the nearest rotation (as rigid as
/// possible); wider limits let the triangle stretch or shrink freely by that much. The rest
/// triangle, from Scene::rest_positions, must not be degenerate.
struct TriangleStrain {
  std::array<int, 3> vertices{0, 0, 0};  ///< particles x0, x1, x2
  double stiffness = 0.0;                ///< k, N/m (energy per rest area per unit strain^2)
  double strain_min = 1.0;               ///< in [0, 1]
  double strain_max = 1.0;               ///< >= 1
};

/// The fields of TriangleStrain, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_TRIANGLE_STRAIN_FIELDS(FIELD)                         \
  FIELD(vertices, "particles x0, x1, x2")                             \
  FIELD(stiffness, "k, N/m (energy per rest area per unit strain^2)") \
  FIELD(strain_min, "in [0, 1]")                                      \
  FIELD(strain_max, ">= 1")
/// @cond
STABINT_FIELD_TABLE_(TriangleStrain, STABINT_TRIANGLE_STRAIN_FIELDS,
                     "Membrane strain of a triangle, singular values kept in [strain_min, strain_max].")
/// @endcond

/// Bending across the edge (vertices[0], vertices[1]) shared by the triangles
/// (vertices[0], vertices[1], vertices[2]) and (vertices[1], vertices[0], vertices[3]):
/// E = w/2 (|K x| - |K x_rest|)^2 with K x = sum_i K_i x_i the cotangent-weight discrete Laplacian
/// of the hinge (its mean-curvature vector; Bergou et al. 2006) and w = 3 k / (A_0 + A_1) with
/// A_0, A_1 the rest areas of the two triangles. As in Projective Dynamics, K x is projected onto
/// the rest mean-curvature magnitude, so a flat or a curved rest shape has zero energy, and
/// rigid motions change nothing. The rest triangles must not be degenerate, nor folded onto
/// each other (a rest dihedral angle beyond 90 degrees).
struct BendingHinge {
  std::array<int, 4> vertices{0, 0, 0, 0};  ///< the edge's two particles, then the two opposite ones
  double stiffness = 0.0;                   ///< k, J
};

/// The fields of BendingHinge, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_BENDING_HINGE_FIELDS(FIELD)                               \
  FIELD(vertices, "the edge's two particles, then the two opposite ones") \
  FIELD(stiffness, "k, J")
/// @cond
STABINT_FIELD_TABLE_(BendingHinge, STABINT_BENDING_HINGE_FIELDS, "Bending across the edge (vertices[0], vertices[1]).")
/// @endcond

/// Target of a pin: q(t) = position + velocity t + amplitude sin(2 pi frequency t).
/// A target with zero velocity and zero amplitude is static.
struct PinTarget {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();   ///< m, the target at t = 0 (without the sine)
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();   ///< m/s
  Eigen::Vector3d amplitude = Eigen::Vector3d::Zero();  ///< m, of the sine
  double frequency = 0.0;                               ///< Hz

  /// q(t).
  Eigen::Vector3d at(double t) const;
  /// True when the target moves (a non-zero velocity, or a sine with non-zero amplitude and frequency).
  bool moving() const;
};

/// The fields of PinTarget, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_PIN_TARGET_FIELDS(FIELD)                       \
  FIELD(position, "m, the target at t = 0 (without the sine)") \
  FIELD(velocity, "m/s")                                       \
  FIELD(amplitude, "m, of the sine")                           \
  FIELD(frequency, "Hz")
/// @cond
STABINT_FIELD_TABLE_(PinTarget, STABINT_PIN_TARGET_FIELDS,
                     "q(t) = position + velocity t + amplitude sin(2 pi frequency t).")
/// @endcond

/// Zero-rest-length spring from a particle to a (possibly moving) target:
/// E = k/2 |x_vertex - q(t)|^2.
struct Pin {
  int vertex = 0;          ///< the pinned particle
  double stiffness = 0.0;  ///< k, N/m
  PinTarget target;        ///< q(t)
};

/// The fields of Pin, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_PIN_FIELDS(FIELD)      \
  FIELD(vertex, "the pinned particle") \
  FIELD(stiffness, "k, N/m")           \
  FIELD(target, "q(t)")
/// @cond
STABINT_FIELD_TABLE_(Pin, STABINT_PIN_FIELDS,
                     "Zero-rest-length spring from a particle to a target: E = k/2 |x - q(t)|^2.")
/// @endcond

/// A force applied to each listed particle (all particles when the list is empty), in newtons:
/// f(t) = force + rate t + amplitude sin(2 pi frequency t). Treated as the potential -f(t).x.
struct ForceField {
  std::vector<int> particles;                           ///< where it acts; empty: every particle
  Eigen::Vector3d force = Eigen::Vector3d::Zero();      ///< N, at t = 0 (without the sine)
  Eigen::Vector3d rate = Eigen::Vector3d::Zero();       ///< N/s
  Eigen::Vector3d amplitude = Eigen::Vector3d::Zero();  ///< N, of the sine
  double frequency = 0.0;                               ///< Hz

  /// f(t).
  Eigen::Vector3d at(double t) const;
  /// True when f changes with time (a non-zero rate, or a sine with non-zero amplitude and frequency).
  bool timeDependent() const;
};

/// The fields of ForceField, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_FORCE_FIELD_FIELDS(FIELD)                  \
  FIELD(particles, "where it acts; empty: every particle") \
  FIELD(force, "N, at t = 0 (without the sine)")           \
  FIELD(rate, "N/s")                                       \
  FIELD(amplitude, "N, of the sine")                       \
  FIELD(frequency, "Hz")
/// @cond
STABINT_FIELD_TABLE_(ForceField, STABINT_FORCE_FIELD_FIELDS,
                     "f(t) = force + rate t + amplitude sin(2 pi frequency t) on `particles` (all when empty).")
/// @endcond

/// The collider shapes, `X(Enumerator, "name", "doc")` (stabint/enum_list.hpp): the name is the
/// scene file's "shape", the doc says which fields of Collider describe it. The kernels compare
/// with these values.
#define STABINT_COLLIDER_SHAPE_VALUES(X)                                                        \
  X(Plane, "plane", "the half-space behind a plane: a point `center` and the outward `normal`") \
  X(Sphere, "sphere", "a ball: `center`, `radius`")                                             \
  X(Box, "box", "an axis-aligned box: `center`, `half_extents`")                                \
  X(Capsule, "capsule", "the points within `radius` of the segment from `center` to `end`")     \
  X(Mesh, "mesh", "the inside of a closed triangle mesh: `mesh_vertices`, `mesh_triangles`")

/// Shape of a Collider (what each is: STABINT_COLLIDER_SHAPE_VALUES).
enum class ColliderShape { STABINT_COLLIDER_SHAPE_VALUES(STABINT_ENUMERATOR_) };
/// Number of ColliderShape values (they run from 0).
constexpr int kColliderShapeCount = 0 STABINT_COLLIDER_SHAPE_VALUES(STABINT_ENUM_ONE_);
/// The value's name in STABINT_COLLIDER_SHAPE_VALUES ("plane", "sphere", ...); "?" for a value outside
/// the enum.
constexpr const char* colliderShapeName(ColliderShape shape) {
  return enumName_(shape, {STABINT_COLLIDER_SHAPE_VALUES(STABINT_ENUM_NAME_)});
}
/// Parses a name as printed by colliderShapeName (case-insensitive); throws InvalidInputError.
ColliderShape parseColliderShape(const std::string& name);

/// A rigid obstacle that no particle may enter (docs/method.md, "Contact"). The particles it acts
/// on (every particle of the scene by default) collide with it through the contact energy
/// E = w_j/2 |x_j - p_j|^2, p_j the closest point of the collider's outside (x_j itself out of
/// contact, so E = 0 there), w_j = stiffness * m_j + elastic_ratio * D_j while the particle is
/// near the collider (the contact set, chosen at each step's start; 0 elsewhere), D_j the
/// stiffness of the particle's own elements (the diagonal of their global matrix at j). The collider translates with
/// `velocity` (0: static): its geometry at time t is that at t = 0 moved by velocity * t, until a running Simulator
/// moves it (Simulator::setColliderPosition, setColliderVelocity).
struct Collider {
  ColliderShape shape = ColliderShape::Plane;  ///< which of the fields below describe it
  /// Plane: a point of the plane; sphere and box: the center; capsule: one end of its axis.
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();       ///< plane: the outward normal (length > 0)
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();  ///< box (axis-aligned): half sizes, > 0
  Eigen::Vector3d end = Eigen::Vector3d::Zero();           ///< capsule: the other end of its axis
  double radius = 0.0;                                     ///< sphere and capsule, > 0
  /// Mesh: the vertices (where Collider::center is its reference point; the mesh moves with it)
  /// and the triangles, a closed surface with every triangle counter-clockwise seen from outside
  /// (each edge shared by two triangles that run it in opposite directions), at least 4.
  ///@{
  Eigen::MatrixX3d mesh_vertices;
  std::vector<std::array<int, 3>> mesh_triangles;
  ///@}
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< m/s
  double friction = 0.0;                               ///< Coulomb coefficient mu >= 0 (0: frictionless)
  /// Contact weight per unit of particle mass, 1/s^2 (> 0): a particle at rest on a collider
  /// under gravity g sinks about |g| / stiffness into it.
  double stiffness = 1e4;
  /// The contact weight's share of the stiffness D_j of the particle's elements, dimensionless
  /// (>= 0): at the default 1 a pair is at least as stiff as the elements that press its particle
  /// into the collider, so a heavy or stiff body stops on its contact layer within the step
  /// whatever its mass, material and mesh; 0 leaves the per-mass weight alone (a soft contact).
  double elastic_ratio = 1.0;
  /// Coefficient of restitution in [0, 1]: the share of an impact's normal speed a body keeps
  /// off this collider. The final projection out of it (docs/method.md, "Contact",
  /// "Restitution") removes energy; 1 - restitution^2 of that is booked as lost (H* drops with
  /// it), the rest is the energy the bounce keeps, and the energy-tracking integrator gives it
  /// back. 1 (default): an elastic contact, the body's material decides the bounce; 0: a fully
  /// inelastic one. BE and BDF2 damp the bounce whatever it is.
  double restitution = 1.0;
  /// The particles it acts on: `num_particles` of them from `first_particle` on, or, when
  /// num_particles is -1 (the default), every particle of the scene. A batch
  /// (include/stabint/batch.hpp) gives each scene's colliders that scene's particles.
  ///@{
  int first_particle = 0;
  int num_particles = -1;
  ///@}

  /// True when `velocity` is not zero.
  bool moving() const { return !velocity.isZero(0.0); }
};

/// The fields of Collider, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_COLLIDER_FIELDS(FIELD)                                                                   \
  FIELD(shape, "which of the fields below describe it")                                                  \
  FIELD(center, "plane: a point of it; sphere and box: the center; capsule: one end of its axis")        \
  FIELD(normal, "plane: the outward normal (length > 0)")                                                \
  FIELD(half_extents, "box (axis-aligned): half sizes, > 0")                                             \
  FIELD(end, "capsule: the other end of its axis")                                                       \
  FIELD(radius, "sphere and capsule, > 0")                                                               \
  FIELD(mesh_vertices, "mesh: (n, 3) vertices, moving with center")                                      \
  FIELD(mesh_triangles, "mesh: (m, 3) triangles of a closed surface, counter-clockwise from outside")    \
  FIELD(velocity, "translation in m/s (0: static)")                                                      \
  FIELD(friction, "Coulomb coefficient mu >= 0 (0: frictionless)")                                       \
  FIELD(stiffness, "contact weight per unit of particle mass, 1/s^2 (> 0)")                              \
  FIELD(elastic_ratio, "contact weight per unit of the particle's element stiffness (>= 0; default 1)")  \
  FIELD(restitution, "share of the normal speed an impact keeps, in [0, 1] (default 1: elastic)")        \
  FIELD(first_particle, "the first particle it acts on (with num_particles; a batch sets each scene's)") \
  FIELD(num_particles, "how many particles from first_particle it acts on; -1 (default): every particle")
/// @cond
STABINT_FIELD_TABLE_(
    Collider, STABINT_COLLIDER_FIELDS,
    "A rigid obstacle the scene's particles, or a range of them, collide with (docs/method.md, 'Contact').")
/// @endcond

/// A group of particles damped together by momentum-preserving velocity damping (docs/method.md
/// section 6): each velocity moves toward the body's rigid velocity by the factor `damping` in
/// [0, 1] per step. 0 disables it.
struct Body {
  std::string name;            ///< for reports and scene files; may be empty
  std::vector<int> particles;  ///< the body's particles
  double damping = 0.0;        ///< in [0, 1] per step
};

/// The fields of Body, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_BODY_FIELDS(FIELD)                         \
  FIELD(name, "for reports and scene files; may be empty") \
  FIELD(particles, "the body's particles")                 \
  FIELD(damping, "in [0, 1] per step")
/// @cond
STABINT_FIELD_TABLE_(Body, STABINT_BODY_FIELDS, "Particles damped together (momentum-preserving), damping in [0, 1].")
/// @endcond

/// A complete simulation scene. Rows of `rest_positions`, `positions` and `velocities`, and
/// entries of `masses`, are per particle.
struct Scene {
  std::string name;                 ///< for reports and scene files; may be empty
  Eigen::MatrixX3d rest_positions;  ///< rest shape used by tets (springs carry their own length)
  Eigen::MatrixX3d positions;       ///< initial positions x_0
  Eigen::MatrixX3d velocities;      ///< initial velocities v_0
  Eigen::VectorXd masses;           ///< lumped masses, > 0 (pinned particles included)

  ///@{
  /// The elements, one list per kind (docs/elements.md).
  std::vector<Spring> springs;
  std::vector<Tet> tets;
  std::vector<TriangleStrain> triangle_strains;
  std::vector<BendingHinge> bending_hinges;
  std::vector<Pin> pins;
  ///@}
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, -9.81, 0.0);  ///< m/s^2
  std::vector<ForceField> force_fields;                        ///< time-dependent external forces
  std::vector<Body> bodies;                                    ///< damping groups
  std::vector<Collider> colliders;                             ///< rigid obstacles
  /// The surface, for renderers, OBJ output and mass lumping (cloth grids and OBJ meshes fill
  /// it); it exerts no force of its own. May be empty.
  std::vector<std::array<int, 3>> triangles;

  /// Rows of `positions`.
  int numParticles() const { return static_cast<int>(positions.rows()); }
};

/// The fields of Scene, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_SCENE_FIELDS(FIELD)                                             \
  FIELD(name, "for reports and scene files; may be empty")                      \
  FIELD(rest_positions, "(n, 3) rest shape used by tets, triangles and hinges") \
  FIELD(positions, "(n, 3) initial positions")                                  \
  FIELD(velocities, "(n, 3) initial velocities")                                \
  FIELD(masses, "(n,) lumped masses, > 0")                                      \
  FIELD(springs, "the springs")                                                 \
  FIELD(tets, "the tets")                                                       \
  FIELD(triangle_strains, "the triangle strains")                               \
  FIELD(bending_hinges, "the bending hinges")                                   \
  FIELD(pins, "the pins")                                                       \
  FIELD(gravity, "(3,) gravity in m/s^2")                                       \
  FIELD(force_fields, "time-dependent external forces")                         \
  FIELD(bodies, "damping groups")                                               \
  FIELD(colliders, "rigid obstacles")                                           \
  FIELD(triangles, "(m, 3) surface triangles for rendering and mass lumping; no force of their own")
/// @cond
STABINT_FIELD_TABLE_(Scene, STABINT_SCENE_FIELDS, "A simulation scene.")
/// @endcond

/// Checks a scene: matrix shapes agree, all values finite, masses > 0, indices in range, no
/// element using a particle twice, stiffness >= 0, rest lengths >= 0, rest volumes > 0, rest
/// tets and triangles not degenerate (zero relative to their size: |V| <= 1e-12 L^3 and
/// A <= 1e-12 L^2 for the longest edge L, the test the mesh loaders apply too; slivers included)
/// and their volume or area finite, hinges not folded, strain limits around 1, damping in [0, 1].
/// Finite values that would overflow are refused too: coordinates, speeds, gravity, rest
/// lengths, pin targets, force fields and frequencies may not exceed 1e150 in magnitude, and the
/// energy terms 0.5 m |v|^2 (per particle and in all), M |g| size (M the total mass, size the
/// diagonal of the scene's bounding box) and k L^2 of each spring and pin (L its rest length or
/// the scene size) must be finite. Throws InvalidInputError naming the offending element or field.
void validateScene(const Scene& scene);

/// Number of elements of all kinds (springs, tets, triangle strains, bending hinges, pins).
int elementCount(const Scene& scene);
/// The non-empty element kinds with their counts, e.g. "14502 springs, 2 pins".
std::string elementSummary(const Scene& scene);

/// Signed rest volume det(Dm)/6 of a tet (positive for a valid element).
double signedVolume(const Eigen::MatrixX3d& rest_positions, const std::array<int, 4>& vertices);

/// Lumped masses from a tet mesh: each tet gives density * volume / 4 to each of its vertices.
/// Particles touched by no tet get `min_mass`. Throws InvalidInputError for an index out of
/// range, a density that is not > 0 and finite, or a tet whose share, or a vertex's sum, is not
/// finite (naming the tet).
Eigen::VectorXd lumpMassesFromTets(const Eigen::MatrixX3d& rest_positions, const std::vector<Tet>& tets, double density,
                                   double min_mass = 1e-6);

/// The surface of a tet mesh whose tets are positively oriented (as validateScene and the mesh
/// loaders require): the faces that only one tet has, wound so that their normals point out of
/// the body, sorted by their corners (the same list on every run). For renderers and OBJ output.
std::vector<std::array<int, 3>> tetSurface(const std::vector<Tet>& tets);

/// Lumped masses from a triangle surface: each triangle gives areal_density * area / 3 to each
/// of its vertices. Particles touched by no triangle get `min_mass`. Throws as lumpMassesFromTets,
/// and for a degenerate (flat) or overflowing rest triangle (naming it).
Eigen::VectorXd lumpMassesFromTriangles(const Eigen::MatrixX3d& rest_positions,
                                        const std::vector<std::array<int, 3>>& triangles, double areal_density,
                                        double min_mass = 1e-6);

/// Springs of a cloth from a triangle mesh: one structural spring per edge, and one bending
/// spring across each interior edge joining the two opposite vertices. Rest lengths from
/// `rest_positions`.
std::vector<Spring> clothSpringsFromTriangles(const Eigen::MatrixX3d& rest_positions,
                                              const std::vector<std::array<int, 3>>& triangles,
                                              double stretch_stiffness, double bend_stiffness);

/// The cloth models, `X(Enumerator, "name", "doc")` (stabint/enum_list.hpp): the name is the
/// scene file's "model".
#define STABINT_CLOTH_MODELS(X)                                                                                \
  X(Springs, "springs", "springs along edges and across interior edges (the grid builder adds shear springs)") \
  X(Triangles, "triangles", "a TriangleStrain per surface triangle and a BendingHinge per interior edge")

/// How a cloth resists deformation: springs or triangle elements (what each is:
/// STABINT_CLOTH_MODELS).
enum class ClothModel { STABINT_CLOTH_MODELS(STABINT_ENUMERATOR_) };
/// Number of ClothModel values (they run from 0).
constexpr int kClothModelCount = 0 STABINT_CLOTH_MODELS(STABINT_ENUM_ONE_);
/// The value's name in STABINT_CLOTH_MODELS ("springs", "triangles"); "?" for a value outside the
/// enum.
constexpr const char* clothModelName(ClothModel model) {
  return enumName_(model, {STABINT_CLOTH_MODELS(STABINT_ENUM_NAME_)});
}
/// Parses a name as printed by clothModelName (case-insensitive); throws InvalidInputError.
ClothModel parseClothModel(const std::string& name);

/// The triangle-element cloth on `scene.triangles`: appends triangleStrainsFromTriangles and
/// bendingHingesFromTriangles of them.
void addTriangleClothElements(Scene& scene, double strain_stiffness, double strain_min, double strain_max,
                              double hinge_stiffness);

/// One TriangleStrain per triangle.
std::vector<TriangleStrain> triangleStrainsFromTriangles(const std::vector<std::array<int, 3>>& triangles,
                                                         double stiffness, double strain_min = 1.0,
                                                         double strain_max = 1.0);

/// One BendingHinge per interior edge of a triangle mesh (an edge shared by exactly two
/// triangles), edge vertices in ascending order.
std::vector<BendingHinge> bendingHingesFromTriangles(const std::vector<std::array<int, 3>>& triangles,
                                                     double stiffness);

}  // namespace stabint
