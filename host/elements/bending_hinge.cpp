// Bending hinge: the edge (x0, x1) shared by the triangles (x0, x1, x2) and (x1, x0, x3).
// A x = K x = sum_i K_i x_i with the cotangent weights of the rest hinge (Bergou et al. 2006)
//   K = [c1 + c3, c0 + c2, -(c0 + c1), -(c2 + c3)],
// c0, c1 the cotangents at x0, x1 in triangle (x0, x1, x2), c2, c3 those in (x1, x0, x3): the
// discrete mean-curvature vector, zero for any flat (or rigidly moved) hinge since sum K_i = 0
// and K x vanishes on the plane of a flat rest. w = 3 k / (A_0 + A_1); the projection holds
// |K x| at its rest value |K x_rest| (Projective Dynamics' bending constraint), so
// params = (w, |K x_rest|, rest direction) and the projection is the spring's.
#include "elements/element_kind.hpp"
#include "elements/projections.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace stabint {
namespace {

using validation::invalid;

Eigen::Vector3d restPoint(const Scene& scene, int vertex) { return scene.rest_positions.row(vertex).transpose(); }

// Cotangent of the angle at `apex` between the directions to a and b.
double cotangent(const Eigen::Vector3d& apex, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d u = a - apex, v = b - apex;
  return u.dot(v) / u.cross(v).norm();
}

double area(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

struct BendingHingeKind : KindDefaults<BendingHinge> {
  static constexpr auto kList = &Scene::bending_hinges;
  static constexpr const char* kName = "bending hinge";
  static constexpr const char* kIdentifier = elementKindName(ElementKind::BendingHinge);
  static constexpr int kVertices = 4, kRows = 1;
  static constexpr int kParams = 5;  // w, |K x_rest|, rest direction
  // One element of a local step on one core, in ns (a length and direction; measured by
  // thread_pass_kind/*): the CPU reference weighs a pass by it when it decides whether to put
  // it on threads.
  static constexpr double kElementNs = 12.0;

  static std::array<int*, 4> vertexRefs(BendingHinge& h) {
    return {&h.vertices[0], &h.vertices[1], &h.vertices[2], &h.vertices[3]};
  }

  static void check(const Scene& scene, const BendingHinge& h, const validation::Owner& owner) {
    validation::checkVertexList(h.vertices, scene.numParticles(), owner);
    validation::checkStiffness(h.stiffness, owner);
    const auto& v = h.vertices;
    validation::checkRestTriangle(scene.rest_positions, v[0], v[1], v[2], owner);
    validation::checkRestTriangle(scene.rest_positions, v[1], v[0], v[3], owner);
    // Consistently wound, the two triangles' normals agree for a flat hinge; opposite normals
    // mean the wings lie on the same side of the edge (one flipped onto the other).
    const Eigen::Vector3d x0 = restPoint(scene, v[0]), x1 = restPoint(scene, v[1]);
    const Eigen::Vector3d n0 = (x1 - x0).cross(restPoint(scene, v[2]) - x0);
    const Eigen::Vector3d n1 = (x0 - x1).cross(restPoint(scene, v[3]) - x1);
    if (!(n0.dot(n1) > 0.0)) {
      invalid(owner, ": flipped rest hinge: triangles (", v[0], ", ", v[1], ", ", v[2], ") and (", v[1], ", ", v[0],
              ", ", v[3], ") are folded onto each other (rest dihedral angle beyond 90 degrees)");
    }
  }

  static void coefficients(const Scene& scene, const BendingHinge& h, double* a) {
    const auto& v = h.vertices;
    const Eigen::Vector3d x0 = restPoint(scene, v[0]), x1 = restPoint(scene, v[1]);
    const Eigen::Vector3d x2 = restPoint(scene, v[2]), x3 = restPoint(scene, v[3]);
    const double c0 = cotangent(x0, x1, x2), c1 = cotangent(x1, x0, x2);
    const double c2 = cotangent(x0, x1, x3), c3 = cotangent(x1, x0, x3);
    a[0] = c1 + c3;
    a[1] = c0 + c2;
    a[2] = -(c0 + c1);
    a[3] = -(c2 + c3);
  }

  static void params(const Scene& scene, const BendingHinge& h, double* p) {
    const auto& v = h.vertices;
    const Eigen::Vector3d x0 = restPoint(scene, v[0]), x1 = restPoint(scene, v[1]);
    const Eigen::Vector3d x2 = restPoint(scene, v[2]), x3 = restPoint(scene, v[3]);
    double a[4];
    coefficients(scene, h, a);
    // The same sum, in the same order, as the element pass: a rest state has exactly zero energy.
    Eigen::Vector3d rest = a[0] * x0;
    rest += a[1] * x1;
    rest += a[2] * x2;
    rest += a[3] * x3;
    const double length = rest.norm();
    const Eigen::Vector3d direction = length > 0.0 ? Eigen::Vector3d(rest / length) : Eigen::Vector3d::UnitX();
    p[0] = 3.0 * h.stiffness / (area(x0, x1, x2) + area(x1, x0, x3));
    p[1] = length;
    p[2] = direction.x();
    p[3] = direction.y();
    p[4] = direction.z();
  }

  static double project(const double* ax, const double* params, double* p) {
    return projections::ontoSphere(ax, params, p);
  }

  static std::vector<KindField<BendingHinge>> jsonFields() {
    return {{"stiffness", &BendingHinge::stiffness, 0.0, true}};
  }
};

}  // namespace

template <>
const ElementType& elementTypeOf<ElementKind::BendingHinge>() {
  static const ElementTypeOf<BendingHingeKind> type;
  return type;
}

}  // namespace stabint
