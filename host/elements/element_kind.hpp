#pragma once
// ElementTypeOf<Kind>: an ElementType from a small struct that states what is specific to one
// element type (see host/elements/spring.cpp for the shortest one, docs/elements.md for the
// how-to). A Kind derives from KindDefaults<Element> (Element: the public struct of
// include/stabint/scene.hpp) and provides:
//
//   static constexpr auto kList = &Scene::tets;    where a scene keeps them
//   static constexpr const char* kName, kIdentifier;
//   static constexpr int kVertices, kRows, kParams;
//   static std::array<int*, kVertices> vertexRefs(Element&);
//   static void check(const Scene&, const Element&, const validation::Owner&);
//   static void params(const Scene&, const Element&, double* params);     // params[0] = weight
//   static double project(const double* ax, const double* params, double* p);  // energy
//   static constexpr double kElementNs;  // one element of a local step on one core, ns (measured)
// and either
//   static constexpr std::array<double, kRows * kVertices> kCoefficients;  (kSharedCoefficients)
// or
//   static void coefficients(const Scene&, const Element&, double* a);    // R by K, row-major
// plus, to differ from KindDefaults: kTerm, kMayDependOnTime with
//   static bool timeDependent(const RunningScene&);
//   static void paramsAt(const RunningScene&, int element, double t, double* params);
// and
// jsonFields() for the generic JSON form. The CPU passes that ElementTypeOf runs over a block are
// in kind_passes.hpp.
#include "elements/element_type.hpp"
#include "elements/kind_passes.hpp"
#include "elements/projections.hpp"
#include "common/validation.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cstddef>
#include <type_traits>
#include <vector>

namespace stabint {

/// w/2 ||ax - p||^2 over `count` reals: the energy of an element whose type has no cheaper or
/// more accurate form of its own.
inline double halfWeightedSquaredDistance(double w, const double* ax, const double* p, int count) {
  double sum = 0.0;
  for (int i = 0; i < count; ++i) sum += (ax[i] - p[i]) * (ax[i] - p[i]);
  return 0.5 * w * sum;
}

/// A_e of a simplex with D edges from its first vertex: A x = F^T = G^T X with the (D + 1) by D
/// G = [-1 ... -1; I] Dm^-1 (so that F = Ds Dm^-1 = X G for X = [x0 ... xD]); written to `a`
/// as D by (D + 1), row-major. Tets (D = 3) and triangle strain (D = 2) share it.
template <int D>
void simplexCoefficients(const Eigen::Matrix<double, D, D>& dm_inverse, double* a) {
  for (int r = 0; r < D; ++r) {
    a[(D + 1) * r] = -dm_inverse.col(r).sum();
    for (int k = 0; k < D; ++k) a[(D + 1) * r + k + 1] = dm_inverse(k, r);
  }
}

/// A numeric member of an element struct in the generic JSON form.
template <class Element>
struct KindField {
  const char* key;
  double Element::*member;
  double default_value;
  bool required;
};

/// Whether an element struct has a `double stiffness` member (every type so far; a type without
/// one refuses run-time stiffness changes).
template <class Element, class = void>
struct HasStiffness : std::false_type {};
template <class Element>
struct HasStiffness<Element, std::void_t<decltype(std::declval<Element&>().stiffness)>>
    : std::is_same<decltype(std::declval<Element&>().stiffness), double> {};

template <class ElementStruct>
struct KindDefaults {
  using Element = ElementStruct;
  static constexpr bool kSharedCoefficients = false;
  static constexpr EnergyTerm kTerm = EnergyTerm::Internal;
  static constexpr bool kMayDependOnTime = false;
  static std::vector<KindField<Element>> jsonFields() { return {}; }
};

template <class Kind>
class ElementTypeOf final : public ElementType {
  using Element = typename Kind::Element;
  static constexpr int K = Kind::kVertices;
  static constexpr int R = Kind::kRows;
  static constexpr int P = Kind::kParams;

  static std::array<int, K> vertexTuple(const Element& element) {
    Element copy = element;
    std::array<int, K> out{};
    const std::array<int*, K> refs = Kind::vertexRefs(copy);
    for (int k = 0; k < K; ++k) out[k] = *refs[k];
    return out;
  }
  static const std::vector<Element>& list(const Scene& scene) { return scene.*Kind::kList; }

 public:
  const char* name() const override { return Kind::kName; }
  const char* identifier() const override { return Kind::kIdentifier; }
  ElementShape shape() const override { return {K, R, P, Kind::kSharedCoefficients}; }
  std::vector<double> sharedCoefficients() const override {
    if constexpr (Kind::kSharedCoefficients) return {Kind::kCoefficients.begin(), Kind::kCoefficients.end()};
    return {};
  }
  EnergyTerm term() const override { return Kind::kTerm; }
  double elementCost() const override { return Kind::kElementNs; }

  int count(const Scene& scene) const override { return static_cast<int>(list(scene).size()); }

  void validate(const Scene& scene) const override {
    const std::vector<Element>& elements = list(scene);
    for (std::size_t i = 0; i < elements.size(); ++i) {
      Kind::check(scene, elements[i], validation::Owner{Kind::kName, i});
    }
  }

  ElementBlock build(const Scene& scene) const override {
    const std::vector<Element>& elements = list(scene);
    ElementBlock block;
    block.type = this;
    block.count = static_cast<int>(elements.size());
    block.vertices.reserve(K * elements.size());
    block.params.resize(P * elements.size());
    if constexpr (Kind::kSharedCoefficients) {
      block.coefficients.assign(Kind::kCoefficients.begin(), Kind::kCoefficients.end());
    } else {
      block.coefficients.resize(R * K * elements.size());
    }
    for (std::size_t e = 0; e < elements.size(); ++e) {
      for (int v : vertexTuple(elements[e])) block.vertices.push_back(v);
      if constexpr (!Kind::kSharedCoefficients) Kind::coefficients(scene, elements[e], &block.coefficients[R * K * e]);
      Kind::params(scene, elements[e], &block.params[P * e]);
    }
    if constexpr (ProjectsLanes<Kind>::value) {
      if (block.count > 0) {
        block.lane_vertices = laneLayout(block.vertices, block.count, K);
        if constexpr (!Kind::kSharedCoefficients)
          block.lane_coefficients = laneLayout(block.coefficients, block.count, R * K);
      }
    }
    return block;
  }

  bool timeDependent(const RunningScene& data) const override {
    if constexpr (Kind::kMayDependOnTime) return Kind::timeDependent(data);
    (void)data;
    return false;
  }

  void paramsAt(const RunningScene& data, double t, std::vector<double>& params) const override {
    const std::vector<Element>& elements = list(data.scene());
    params.resize(P * elements.size());
    const int block = data.blockIndex(*this);
    for (std::size_t e = 0; e < elements.size(); ++e) {
      if constexpr (Kind::kMayDependOnTime) {
        Kind::paramsAt(data, static_cast<int>(e), t, &params[P * e]);
      } else {
        Kind::params(data.scene(), elements[e], &params[P * e]);
      }
      // A disabled element has weight 0 (SceneData::setElementEnabled).
      if (!data.elementEnabled(block, static_cast<int>(e))) params[P * e] = 0.0;
    }
  }

  bool hasStiffness() const override { return HasStiffness<Element>::value; }
  double stiffness(const Scene& scene, int element) const override {
    if constexpr (HasStiffness<Element>::value) return list(scene)[element].stiffness;
    (void)scene, (void)element;
    return 0.0;
  }
  void setStiffness(Scene& scene, int element, double stiffness) const override {
    if constexpr (HasStiffness<Element>::value) (scene.*Kind::kList)[element].stiffness = stiffness;
    (void)scene, (void)element, (void)stiffness;
  }
  void elementParams(const Scene& scene, int element, double* params) const override {
    Kind::params(scene, list(scene)[element], params);
  }

  void appendShifted(Scene& into, const Scene& part, int offset) const override {
    std::vector<Element>& target = into.*Kind::kList;
    for (Element element : list(part)) {
      for (int* v : Kind::vertexRefs(element)) *v += offset;
      target.push_back(element);
    }
  }

  double project(const double* ax, const double* params, double* p) const override {
    return Kind::project(ax, params, p);
  }

  double passRange(const ElementBlock& block, const std::vector<double>& params, const Eigen::MatrixX3d& x, int first,
                   int count, int flags, Eigen::MatrixX3d* out) const override {
    return kindPass<Kind>(block, params, x, first, count, flags, out);
  }

  bool elementResults(const ElementBlock& block, const std::vector<double>& params, const Eigen::MatrixX3d& x,
                      int first, int count, int flags, double* energies, double* contributions) const override {
    kindElementResults<Kind>(block, params, x, first, count, flags, energies, contributions);
    return true;
  }

  bool ownedResults(const ElementBlock& block, const std::vector<double>& params, const Eigen::MatrixX3d& x, int first,
                    int count, int flags, int lo, int hi, Eigen::MatrixX3d* out, double* energies) const override {
    kindOwnedResults<Kind>(block, params, x, first, count, flags, lo, hi, out, energies);
    return true;
  }

  std::vector<Field> jsonFields() const override {
    std::vector<Field> fields;
    for (const KindField<Element>& f : Kind::jsonFields()) {
      fields.push_back({f.key, f.default_value, f.required});
    }
    return fields;
  }

  void record(const Scene& scene, int i, std::vector<int>& vertices, std::vector<double>& values) const override {
    const Element& element = list(scene)[i];
    const std::array<int, K> tuple = vertexTuple(element);
    vertices.assign(tuple.begin(), tuple.end());
    values.clear();
    for (const KindField<Element>& f : Kind::jsonFields()) values.push_back(element.*f.member);
  }

  void appendRecord(Scene& scene, const std::vector<int>& vertices, const std::vector<double>& values) const override {
    Element element{};
    const std::array<int*, K> refs = Kind::vertexRefs(element);
    for (int k = 0; k < K; ++k) *refs[k] = vertices.at(k);
    const std::vector<KindField<Element>> fields = Kind::jsonFields();
    for (std::size_t i = 0; i < fields.size(); ++i) element.*fields[i].member = values.at(i);
    (scene.*Kind::kList).push_back(element);
  }
};

}  // namespace stabint
