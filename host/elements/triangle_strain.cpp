// Triangle strain (membrane): E = k A/2 ||F - P||_F^2 with F = Ds Dm^-1 (3 by 2) against the
// rest triangle in its own plane and P = U clamp(S, s_min, s_max) V^T for F = U S V^T.
// A x = F^T = G^T X with the 3 by 2 G = [[-1,-1],[1,0],[0,1]] Dm^-1, w = k A,
// params (k A, s_min, s_max).
#include "elements/element_kind.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>

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

struct Svd2 {
  Eigen::Matrix2d U, V;
  Eigen::Vector2d s;
};

Eigen::Matrix2d rotation2(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Eigen::Matrix2d r;
  r << c, -s, s, c;
  return r;
}

// M = U diag(s) V^T in closed form for det M >= 0 (Blinn, "Consider the lowly 2x2 matrix"):
// M = [[E + F, G - H], [G + H, E - F]] is a rotation by (a2 + a1)/2 after diag(s1, s2) after a
// rotation by (a2 - a1)/2, with s = sqrt(E^2 + H^2) +- sqrt(F^2 + G^2), a1 = atan2(G, F),
// a2 = atan2(H, E).
Svd2 svd2(const Eigen::Matrix2d& m) {
  const double e = 0.5 * (m(0, 0) + m(1, 1)), f = 0.5 * (m(0, 0) - m(1, 1));
  const double g = 0.5 * (m(1, 0) + m(0, 1)), h = 0.5 * (m(1, 0) - m(0, 1));
  const double q = std::hypot(e, h), r = std::hypot(f, g);
  const double a1 = std::atan2(g, f), a2 = std::atan2(h, e);
  Svd2 out;
  out.s = Eigen::Vector2d(q + r, q - r);
  out.U = rotation2(0.5 * (a2 + a1));
  out.V = rotation2(0.5 * (a2 - a1)).transpose();
  return out;
}

struct TriangleStrainKind : KindDefaults<TriangleStrain> {
  static constexpr auto kList = &Scene::triangle_strains;
  static constexpr const char* kName = "triangle strain";
  static constexpr const char* kIdentifier = "triangle_strain";
  static constexpr int kVertices = 3, kRows = 2;
  static constexpr int kParams = 3;  // k A, s_min, s_max

  static std::array<int*, 3> vertexRefs(TriangleStrain& t) {
    return {&t.vertices[0], &t.vertices[1], &t.vertices[2]};
  }

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
    // ax holds F^T row-major, i.e. F (3 by 2) column-major; so does p for P.
    const Eigen::Map<const Eigen::Matrix<double, 3, 2>> F(ax);
    // F = Q R (Gram-Schmidt, twice for orthogonality), then the closed-form SVD of the 2 by 2
    // R: no squared singular values, independent of the kernel's method (eigenvectors of
    // F^T F), and a fraction of the cost of an iterative 3 by 2 SVD.
    Eigen::Matrix<double, 3, 2> Q;
    Eigen::Matrix2d R = Eigen::Matrix2d::Zero();
    R(0, 0) = F.col(0).norm();
    Q.col(0) = R(0, 0) > 0.0 ? Eigen::Vector3d(F.col(0) / R(0, 0)) : Eigen::Vector3d::UnitX();
    Eigen::Vector3d w = F.col(1) - Q.col(0).dot(F.col(1)) * Q.col(0);
    w -= Q.col(0).dot(w) * Q.col(0);
    R(0, 1) = Q.col(0).dot(F.col(1));
    R(1, 1) = w.norm();
    Q.col(1) = R(1, 1) > 1e-300 ? Eigen::Vector3d(w / R(1, 1)) : Q.col(0).unitOrthogonal();
    const Svd2 svd = svd2(R);
    const Eigen::Vector2d s = svd.s.cwiseMax(params[1]).cwiseMin(params[2]);
    Eigen::Map<Eigen::Matrix<double, 3, 2>> projection(p);
    projection = Q * svd.U * s.asDiagonal() * svd.V.transpose();
    return halfWeightedSquaredDistance(params[0], ax, p, 6);
  }

  static std::vector<KindField<TriangleStrain>> jsonFields() {
    return {{"stiffness", &TriangleStrain::stiffness, 0.0, true},
            {"strain_min", &TriangleStrain::strain_min, 1.0, false},
            {"strain_max", &TriangleStrain::strain_max, 1.0, false}};
  }
};

}  // namespace

const ElementType& triangleStrainElementType() {
  static const ElementTypeOf<TriangleStrainKind> type;
  return type;
}

}  // namespace stabint
