// Triangle strain (membrane): E = k A/2 ||F - P||_F^2 with F = Ds Dm^-1 (3 by 2) against the
// rest triangle in its own plane and P = U clamp(S, s_min, s_max) V^T for F = U S V^T.
// A x = F^T = G^T X with the 3 by 2 G = [[-1,-1],[1,0],[0,1]] Dm^-1, w = k A,
// params (k A, s_min, s_max).
#include "elements/element_kind.hpp"
#include "elements/projections.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>

namespace stabint {
namespace {

using validation::invalid;

// The rest edges x1 - x0, x2 - x0 in an orthonormal frame of the rest triangle's plane.
Eigen::Matrix2d restEdges2d(const Scene& scene, const TriangleStrain& t) {
  const auto& x = scene.rest_positions;
  const Eigen::Vector3d e1 = (x.row(t.vertices[1]) - x.row(t.vertices[0])).transpose();
  const Eigen::Vector3d e2 = (x.row(t.vertices[2]) - x.row(t.vertices[0])).transpose();
  const Eigen::Vector3d t1 = e1.normalized();
  const Eigen::Vector3d t2 = (e2 - e2.dot(t1) * t1).normalized();
  Eigen::Matrix2d dm;
  dm << e1.dot(t1), e2.dot(t1), 0.0, e2.dot(t2);
  return dm;
}

struct TriangleStrainKind : KindDefaults<TriangleStrain> {
  static constexpr auto kList = &Scene::triangle_strains;
  static constexpr const char* kName = "triangle strain";
  static constexpr const char* kIdentifier = elementKindName(ElementKind::TriangleStrain);
  static constexpr int kVertices = 3, kRows = 2;
  static constexpr int kParams = 3;  // k A, s_min, s_max
  // One element of a local step on one core, in ns (a 3 x 2 singular value decomposition; measured by
  // thread_pass_kind/*): the CPU reference weighs a pass by it when it decides whether to put
  // it on threads.
  static constexpr double kElementNs = 90.0;

  static std::array<int*, 3> vertexRefs(TriangleStrain& t) { return {&t.vertices[0], &t.vertices[1], &t.vertices[2]}; }

  static void check(const Scene& scene, const TriangleStrain& t, const validation::Owner& owner) {
    validation::checkVertexList(t.vertices, scene.numParticles(), owner);
    validation::checkStiffness(t.stiffness, owner);
    if (!(t.strain_min >= 0.0 && t.strain_min <= 1.0 && t.strain_max >= 1.0 && std::isfinite(t.strain_max))) {
      invalid(owner, ": strain limits [", t.strain_min, ", ", t.strain_max,
              "] must satisfy 0 <= strain_min <= 1 <= strain_max (the rest state lies inside)");
    }
    validation::checkRestTriangle(scene.rest_positions, t.vertices[0], t.vertices[1], t.vertices[2], owner);
  }

  static void coefficients(const Scene& scene, const TriangleStrain& t, double* a) {
    // check() has guaranteed a non-degenerate rest triangle, so Dm is invertible.
    simplexCoefficients<2>(restEdges2d(scene, t).inverse(), a);
  }

  static void params(const Scene& scene, const TriangleStrain& t, double* p) {
    p[0] = t.stiffness * 0.5 * restEdges2d(scene, t).determinant();
    p[1] = t.strain_min;
    p[2] = t.strain_max;
  }

  static double project(const double* ax, const double* params, double* p) {
    // ax holds F^T row-major: its rows are the columns f0, f1 of F (3 by 2); so does p for P.
    // V from the 2 by 2 F^T F = [[a, b], [b, c]] in closed form (no trigonometry), U and S from
    // Gram-Schmidt on F V: the singular values are lengths, not square roots of eigenvalues, so
    // a small one keeps its digits. The kernel (kernels/triangle_strain.cl) takes the same steps.
    const Eigen::Vector3d f0(ax[0], ax[1], ax[2]), f1(ax[3], ax[4], ax[5]);
    const double a = f0.dot(f0), b = f0.dot(f1), c = f1.dot(f1);
    // v1 = (cs, sn), the eigenvector of the larger eigenvalue l = (a + c)/2 + r, is parallel to
    // (l - c, b) and to (b, l - a); the one whose first term adds two non-negative numbers is
    // free of cancellation. Equal eigenvalues (F a scaled isometry) take v1 = (1, 0).
    const double half_difference = 0.5 * (a - c);
    const double r = std::sqrt(half_difference * half_difference + b * b);
    const double x = half_difference >= 0.0 ? half_difference + r : b;
    const double y = half_difference >= 0.0 ? b : r - half_difference;
    const double length = std::sqrt(x * x + y * y);
    const double cs = length > 0.0 ? x / length : 1.0, sn = length > 0.0 ? y / length : 0.0;
    const Eigen::Vector3d b1 = cs * f0 + sn * f1, b2 = cs * f1 - sn * f0;  // F v1, F v2 (v2 = (-sn, cs))
    const double s1 = std::sqrt(b1.dot(b1));
    const Eigen::Vector3d u1 = s1 > 0.0 ? Eigen::Vector3d(b1 / s1) : Eigen::Vector3d::UnitX();
    // Gram-Schmidt twice keeps u2 orthogonal to u1 when b2 is much shorter than b1.
    Eigen::Vector3d w = b2 - u1.dot(b2) * u1;
    w -= u1.dot(w) * u1;
    const double s2 = std::sqrt(w.dot(w));
    const Eigen::Vector3d u2 =
        s2 > std::numeric_limits<double>::epsilon() * s1 ? Eigen::Vector3d(w / s2) : projections::anyOrthogonal(u1);
    const double t1 = std::clamp(s1, params[1], params[2]), t2 = std::clamp(s2, params[1], params[2]);
    // Row k of P^T = sum_i t_i v_i[k] u_i.
    const Eigen::Vector3d p0 = t1 * cs * u1 - t2 * sn * u2, p1 = t1 * sn * u1 + t2 * cs * u2;
    for (int k = 0; k < 3; ++k) p[k] = p0[k], p[3 + k] = p1[k];
    return halfWeightedSquaredDistance(params[0], ax, p, 6);
  }

  static std::vector<KindField<TriangleStrain>> jsonFields() {
    return {{"stiffness", &TriangleStrain::stiffness, 0.0, true},
            {"strain_min", &TriangleStrain::strain_min, 1.0, false},
            {"strain_max", &TriangleStrain::strain_max, 1.0, false}};
  }
};

}  // namespace

template <>
const ElementType& elementTypeOf<ElementKind::TriangleStrain>() {
  static const ElementTypeOf<TriangleStrainKind> type;
  return type;
}

}  // namespace stabint
