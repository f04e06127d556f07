// Co-rotated tet strain: E = k V/2 ||F - R||_F^2, F = Ds Dm^-1 with Ds = [x1-x0, x2-x0, x3-x0]
// and R the nearest rotation. A x = F^T = G^T X with the 4 by 3
// G = [[-1,-1,-1],[1,0,0],[0,1,0],[0,0,1]] Dm^-1 (so that F = X G for X = [x0 x1 x2 x3]),
// w = k V, p = R^T.
#include "elements/element_kind.hpp"
#include "elements/projections.hpp"

#include <Eigen/LU>

namespace stabint {
namespace {

Eigen::Matrix3d restEdges(const Scene& scene, const Tet& tet) {
  const auto& x = scene.rest_positions;
  const auto& v = tet.vertices;
  Eigen::Matrix3d dm;
  for (int k = 0; k < 3; ++k) dm.col(k) = (x.row(v[k + 1]) - x.row(v[0])).transpose();
  return dm;
}

struct TetKind : KindDefaults<Tet> {
  static constexpr auto kList = &Scene::tets;
  static constexpr const char* kName = "tet";
  static constexpr const char* kIdentifier = elementKindName(ElementKind::Tet);
  static constexpr int kVertices = 4, kRows = 3;
  static constexpr int kParams = 1;  // k V
  // One element of a local step on one core, in ns (a polar decomposition, 16 in SIMD lanes; measured by
  // thread_pass_kind/*): the CPU reference weighs a pass by it when it decides whether to put
  // it on threads.
  static constexpr double kElementNs = 35.0;

  static std::array<int*, 4> vertexRefs(Tet& t) {
    return {&t.vertices[0], &t.vertices[1], &t.vertices[2], &t.vertices[3]};
  }

  static void check(const Scene& scene, const Tet& tet, const validation::Owner& owner) {
    validation::checkVertexList(tet.vertices, scene.numParticles(), owner);
    validation::checkStiffness(tet.stiffness, owner);
    validation::checkRestTet(scene.rest_positions, tet.vertices, owner);
  }

  static void coefficients(const Scene& scene, const Tet& tet, double* a) {
    // check() has guaranteed det(Dm) > 0 and not flat, so the inverse exists.
    simplexCoefficients<3>(restEdges(scene, tet).inverse(), a);
  }

  static void params(const Scene& scene, const Tet& tet, double* p) {
    p[0] = tet.stiffness * restEdges(scene, tet).determinant() / 6.0;
  }

  static double project(const double* ax, const double* params, double* p) {
    // ax holds F^T row-major; the nearest rotation of F^T is R^T, which is p.
    projections::nearestRotation(ax, p);
    return halfWeightedSquaredDistance(params[0], ax, p, 9);
  }

  static void projectLanes(const double (*ax)[projections::kLanes], const double (*params)[projections::kLanes],
                           double (*p)[projections::kLanes], double* energy) {
    projections::nearestRotations(ax, p);
    halfWeightedSquaredDistances<9>(params[0], ax, p, energy);
  }
};

}  // namespace

template <>
const ElementType& elementTypeOf<ElementKind::Tet>() {
  static const ElementTypeOf<TetKind> type;
  return type;
}

}  // namespace stabint
