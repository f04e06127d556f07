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

// GCC 12 warns that Eigen's fixed-size 3 by 2 JacobiSVD may read its singular values
// uninitialized; they are written before any read (a known false positive).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

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
    // The reference path uses Eigen's Jacobi SVD (an oracle independent of the kernel's method).
    const Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>> svd(F, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::Vector2d s = svd.singularValues().cwiseMax(params[1]).cwiseMin(params[2]);
    Eigen::Map<Eigen::Matrix<double, 3, 2>> projection(p);
    projection = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();
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
