// Spring (a, b, rest length r, stiffness k): E = k/2 (|x_a - x_b| - r)^2.
// A x = x_a - x_b (coefficients [1, -1]), w = k, p = r (x_a - x_b)/|x_a - x_b|.
#include "elements/element_kind.hpp"
#include "elements/projections.hpp"

#include <cmath>

namespace stabint {
namespace {

using validation::invalid;

struct SpringKind : KindDefaults<Spring> {
  static constexpr auto kList = &Scene::springs;
  static constexpr const char* kName = "spring";
  static constexpr const char* kIdentifier = elementKindName(ElementKind::Spring);
  static constexpr int kVertices = 2, kRows = 1;
  static constexpr int kParams = 5;  // k, r, rest direction (unit, from b to a)
  // One element of a local step on one core, in ns (its length and direction; measured by
  // thread_pass_kind/*): the CPU reference weighs a pass by it when it decides whether to put
  // it on threads.
  static constexpr double kElementNs = 6.0;
  static constexpr bool kSharedCoefficients = true;
  static constexpr std::array<double, 2> kCoefficients{1.0, -1.0};

  static std::array<int*, 2> vertexRefs(Spring& s) { return {&s.a, &s.b}; }

  static void check(const Scene& scene, const Spring& s, const validation::Owner& owner) {
    const int n = scene.numParticles();
    validation::checkIndex(s.a, n, owner, "a");
    validation::checkIndex(s.b, n, owner, "b");
    if (s.a == s.b) invalid(owner, " joins particle ", s.a, " to itself");
    if (!(s.rest_length >= 0.0) || !std::isfinite(s.rest_length)) {
      invalid(owner, ": rest length ", s.rest_length, " must be >= 0 and finite");
    }
    validation::checkFinite(s.rest_length, owner, "rest length");
    validation::checkStiffness(s.stiffness, owner);
  }

  static void params(const Scene& scene, const Spring& s, double* p) {
    // Coincident endpoints project along the rest direction; +x when that is undefined too.
    Eigen::Vector3d dir = (scene.rest_positions.row(s.a) - scene.rest_positions.row(s.b)).transpose();
    const double len = dir.norm();
    dir = len > 0.0 && std::isfinite(len) ? Eigen::Vector3d(dir / len) : Eigen::Vector3d::UnitX();
    p[0] = s.stiffness;
    p[1] = s.rest_length;
    p[2] = dir.x();
    p[3] = dir.y();
    p[4] = dir.z();
  }

  static double project(const double* ax, const double* params, double* p) {
    return projections::ontoSphere(ax, params, p);
  }
};

}  // namespace

template <>
const ElementType& elementTypeOf<ElementKind::Spring>() {
  static const ElementTypeOf<SpringKind> type;
  return type;
}

}  // namespace stabint
