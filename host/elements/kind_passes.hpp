#pragma once
// The CPU reference's passes of one element kind (ElementTypeOf<Kind>, element_kind.hpp): a
// block's projections, energies and results, in lanes of projections::kLanes elements where the
// kind projects lanes (Kind::projectLanes) and one element at a time otherwise, and the layout
// of its data in lanes.
#include "elements/element_type.hpp"
#include "elements/energy_sum.hpp"
#include "elements/projections.hpp"
#include "common/simd.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cstddef>
#include <type_traits>
#include <vector>

namespace stabint {

/// w/2 ||ax - p||^2 of every lane (halfWeightedSquaredDistance's additions, lane by lane).
template <int Rows>
inline void halfWeightedSquaredDistances(const double* w, const double (*ax)[projections::kLanes],
                                         const double (*p)[projections::kLanes], double* energy) {
  constexpr int W = projections::kLanes;
  STABINT_LANES for (int l = 0; l < W; ++l) {
    double sum = 0.0;
    for (int i = 0; i < Rows; ++i) sum += (ax[i][l] - p[i][l]) * (ax[i][l] - p[i][l]);
    energy[l] = 0.5 * w[l] * sum;
  }
}

/// Whether a Kind projects a group of lanes itself (projectLanes): its elements go through the
/// passes in groups (kindLanes), the others one at a time (kindElement). Lanes pay for the gathers
/// and the transposes around the projection, which a projection as cheap as a spring's does not
/// win back (measured: the 20 x 20 cloth's local step took 1.85x as long in lanes); the tet's
/// rotation does (the tet bar's, 0.5x).
template <class Kind, class = void>
struct ProjectsLanes : std::false_type {};
template <class Kind>
struct ProjectsLanes<Kind, std::void_t<decltype(&Kind::projectLanes)>> : std::true_type {};

/// `per` entries of each element of `flat` (element e's at [per e]) in the lane layout of
/// ElementBlock::lane_vertices and lane_coefficients.
template <class T>
std::vector<T> laneLayout(const std::vector<T>& flat, int count, int per) {
  constexpr int W = projections::kLanes;
  const int groups = (count + W - 1) / W;
  std::vector<T> lanes(std::size_t(groups) * per * W);
  for (int g = 0; g < groups; ++g)
    for (int i = 0; i < per; ++i)
      for (int l = 0; l < W; ++l)
        lanes[(std::size_t(g) * per + i) * W + l] = flat[std::size_t(per) * std::min(W * g + l, count - 1) + i];
  return lanes;
}

/// The group of lanes of a Kind's block that starts at element `group` (a multiple of kLanes,
/// projections.hpp), for its lanes [lo, hi): A_e x of each element, its projection, its energy
/// into energies[l - lo] and, when `write`, the contributions w A_e^T p (or w A_e^T (p - A_e x)
/// with `force`) of its K vertices into c, lane-major (contributionAt). The group reads its
/// vertices and coefficients from the block's lane layout; lanes outside [lo, hi) compute
/// elements whose results are not stored (past the block's end: its last element). Every lane
/// does the same operations in the same order as kernels/element_pass.cl: a result does not
/// depend on the lanes around it.
template <class Kind>
STABINT_TARGET_CLONES_TEMPLATE void kindLanes(const ElementBlock& block, const std::vector<double>& params,
                                              const double* xs, Eigen::Index n, const double* shared, int group, int lo,
                                              int hi, bool write, bool force, double* energies, double* c) {
  constexpr int W = projections::kLanes;
  constexpr int K = Kind::kVertices;
  constexpr int R = Kind::kRows;
  constexpr int P = Kind::kParams;
  const int* vertices = block.lane_vertices.data() + std::size_t(group) * K;
  const double* element_params = params.data();
  int e[W];
  STABINT_LANES for (int l = 0; l < W; ++l) e[l] = std::min(group + l, block.count - 1);
  // The coefficients are read where they lie (a copy to the stack costs more than the loads).
  double shared_lanes[Kind::kSharedCoefficients ? R * K : 1][W];
  const double(*a)[W] = shared_lanes;
  if constexpr (Kind::kSharedCoefficients) {
    for (int i = 0; i < R * K; ++i) STABINT_LANES for (int l = 0; l < W; ++l) shared_lanes[i][l] = shared[i];
  } else {
    a = reinterpret_cast<const double(*)[W]>(block.lane_coefficients.data() + std::size_t(group) * R * K);
  }
  // Sums start from their first term, not from 0: 0.0 + x cannot be folded to x (it differs
  // for x = -0.0), and with the shared coefficients +-1 of springs and pins this loop is then
  // exactly x_a - x_b or x_j.
  double ax[3 * R][W];
  for (int k = 0; k < K; ++k) {
    double x0[W], x1[W], x2[W];
    STABINT_LANES for (int l = 0; l < W; ++l) {
      const int v = vertices[W * k + l];
      x0[l] = xs[v];
      x1[l] = xs[n + v];
      x2[l] = xs[2 * n + v];
    }
    for (int r = 0; r < R; ++r) STABINT_LANES for (int l = 0; l < W; ++l) {
        const double coefficient = a[K * r + k][l];
        ax[3 * r][l] = k == 0 ? coefficient * x0[l] : ax[3 * r][l] + coefficient * x0[l];
        ax[3 * r + 1][l] = k == 0 ? coefficient * x1[l] : ax[3 * r + 1][l] + coefficient * x1[l];
        ax[3 * r + 2][l] = k == 0 ? coefficient * x2[l] : ax[3 * r + 2][l] + coefficient * x2[l];
      }
  }
  double prm[P][W];
  for (int i = 0; i < P; ++i) STABINT_LANES for (int l = 0; l < W; ++l) prm[i][l] = element_params[P * e[l] + i];
  double p[3 * R][W], energy[W];
  Kind::projectLanes(ax, prm, p, energy);
  for (int l = lo; l < hi; ++l) energies[l - lo] = energy[l];
  if (!write) return;
  for (int i = 0; i < 3 * R; ++i)
    STABINT_LANES for (int l = 0; l < W; ++l) p[i][l] = prm[0][l] * (force ? p[i][l] - ax[i][l] : p[i][l]);
  for (int k = 0; k < K; ++k) {
    double c0[W], c1[W], c2[W];
    STABINT_LANES for (int l = 0; l < W; ++l) {
      c0[l] = a[k][l] * p[0][l];
      c1[l] = a[k][l] * p[1][l];
      c2[l] = a[k][l] * p[2][l];
    }
    for (int r = 1; r < R; ++r) STABINT_LANES for (int l = 0; l < W; ++l) {
        c0[l] += a[K * r + k][l] * p[3 * r][l];
        c1[l] += a[K * r + k][l] * p[3 * r + 1][l];
        c2[l] += a[K * r + k][l] * p[3 * r + 2][l];
      }
    // Whole vectors: the consumers read them back lane by lane, which costs loads, where storing
    // them element by element here cost a store per value.
    STABINT_LANES for (int l = 0; l < W; ++l) {
      c[3 * W * k + l] = c0[l];
      c[3 * W * k + W + l] = c1[l];
      c[3 * W * k + 2 * W + l] = c2[l];
    }
  }
}

/// Element e of a Kind's block, for the kinds without projectLanes: A_e x into `ax`, its
/// projection, the energy (returned) and, when `write`, the contributions w A_e^T p (or
/// w A_e^T (p - A_e x) with `force`) of its K vertices into `c` (3 per vertex). Plain arrays with
/// compile-time bounds, the same loops as kernels/element_pass.cl and kindLanes: the compiler
/// unrolls them and keeps A_e x and p_e in registers.
template <class Kind>
inline double kindElement(const ElementBlock& block, const std::vector<double>& params, const double* xs,
                          Eigen::Index n, const double* shared, int e, bool write, bool force, double* c) {
  constexpr int K = Kind::kVertices;
  constexpr int R = Kind::kRows;
  constexpr int P = Kind::kParams;
  constexpr int kStride = Kind::kSharedCoefficients ? 0 : R * K;  // coefficients per element
  const int* v = block.vertices.data() + K * e;
  const double* a = Kind::kSharedCoefficients ? shared : block.coefficients.data() + kStride * e;
  const double* prm = params.data() + P * e;
  // Sums start from their first term, not from 0: 0.0 + x cannot be folded to x (it differs
  // for x = -0.0), and with the shared coefficients +-1 of springs and pins this loop is then
  // exactly x_a - x_b or x_j.
  double ax[3 * R];
  for (int k = 0; k < K; ++k) {
    const double x0 = xs[v[k]], x1 = xs[n + v[k]], x2 = xs[2 * n + v[k]];
    for (int r = 0; r < R; ++r) {
      const double coefficient = a[K * r + k];
      ax[3 * r] = k == 0 ? coefficient * x0 : ax[3 * r] + coefficient * x0;
      ax[3 * r + 1] = k == 0 ? coefficient * x1 : ax[3 * r + 1] + coefficient * x1;
      ax[3 * r + 2] = k == 0 ? coefficient * x2 : ax[3 * r + 2] + coefficient * x2;
    }
  }
  double p[3 * R];
  const double element_energy = Kind::project(ax, prm, p);
  if (!write) return element_energy;
  const double w = prm[0];
  for (int i = 0; i < 3 * R; ++i) p[i] = w * (force ? p[i] - ax[i] : p[i]);
  for (int k = 0; k < K; ++k) {
    double c0 = a[k] * p[0], c1 = a[k] * p[1], c2 = a[k] * p[2];
    for (int r = 1; r < R; ++r) {
      c0 += a[K * r + k] * p[3 * r];
      c1 += a[K * r + k] * p[3 * r + 1];
      c2 += a[K * r + k] * p[3 * r + 2];
    }
    c[3 * k] = c0;
    c[3 * k + 1] = c1;
    c[3 * k + 2] = c2;
  }
  return element_energy;
}

/// Where kindGroup leaves coordinate j of the contribution to vertex k of element group + lo + i
/// in its `c`: lane-major for the kinds that project lanes (3 K kLanes values), element by element
/// from lane lo on for the others (3 K (hi - lo)).
template <class Kind>
constexpr int contributionAt(int lo, int i, int k, int j) {
  if constexpr (ProjectsLanes<Kind>::value) return (3 * k + j) * projections::kLanes + lo + i;
  return 3 * (Kind::kVertices * i + k) + j;
}

/// Elements [group + lo, group + hi) of a Kind's block (group a multiple of kLanes, hi <= kLanes)
/// into energies[l - lo] and (when `write`) c (contributionAt): as one group of lanes, or one at
/// a time.
template <class Kind>
inline void kindGroup(const ElementBlock& block, const std::vector<double>& params, const double* xs, Eigen::Index n,
                      const double* shared, int group, int lo, int hi, bool write, bool force, double* energies,
                      double* c) {
  if constexpr (ProjectsLanes<Kind>::value) {
    kindLanes<Kind>(block, params, xs, n, shared, group, lo, hi, write, force, energies, c);
  } else {
    constexpr int K = Kind::kVertices;
    for (int l = lo; l < hi; ++l)
      energies[l - lo] = kindElement<Kind>(block, params, xs, n, shared, group + l, write, force,
                                           write ? c + 3 * K * (l - lo) : nullptr);
  }
}

/// Calls f(group, lo, hi) for the groups of lanes (aligned at multiples of kLanes) that cover
/// elements [first, first + count), with each group's lanes [lo, hi) in that range, in element
/// order.
template <class F>
inline void forEachGroup(int first, int count, F&& f) {
  constexpr int W = projections::kLanes;
  for (int group = first - first % W; group < first + count; group += W)
    f(group, std::max(first - group, 0), std::min(first + count - group, W));
}

/// The shared coefficients of a Kind (unused when each element has its own).
template <class Kind>
inline void kindSharedCoefficients(double* shared) {
  if constexpr (Kind::kSharedCoefficients) {
    for (int i = 0; i < Kind::kRows * Kind::kVertices; ++i) shared[i] = Kind::kCoefficients[i];
  }
}

/// ElementType::pass of a Kind (ElementTypeOf's, and that of types whose elements are not a
/// Scene list, such as contact): kindGroup per group, the contributions added into `out` in
/// element order, the energies summed by EnergySum's rule.
template <class Kind>
double kindPass(const ElementBlock& block, const std::vector<double>& params, const Eigen::MatrixX3d& x, int first,
                int count, int flags, Eigen::MatrixX3d* out) {
  constexpr int K = Kind::kVertices;
  const bool write = (flags & (kPassProjection | kPassForce)) != 0;
  const bool force = (flags & kPassForce) != 0;
  const Eigen::Index n = x.rows();
  const double* xs = x.data();
  double* os = write ? out->data() : nullptr;
  double shared[Kind::kRows * K];
  kindSharedCoefficients<Kind>(shared);
  EnergySum energy;
  forEachGroup(first, count, [&](int group, int lo, int hi) {
    // (Kind's and projections' constants spelled out: GCC 12 fails on the enclosing function's
    // constexpr locals in a lambda's array bounds.)
    double c[3 * Kind::kVertices * projections::kLanes], energies[projections::kLanes];
    kindGroup<Kind>(block, params, xs, n, shared, group, lo, hi, write, force, energies, c);
    if (flags & kPassEnergy) energy.add(group + lo - first, energies, hi - lo);
    if (!write) return;
    for (int l = 0; l < hi - lo; ++l) {
      const int* v = block.vertices.data() + K * (group + lo + l);
      for (int k = 0; k < K; ++k) {
        os[v[k]] += c[contributionAt<Kind>(lo, l, k, 0)];
        os[n + v[k]] += c[contributionAt<Kind>(lo, l, k, 1)];
        os[2 * n + v[k]] += c[contributionAt<Kind>(lo, l, k, 2)];
      }
    }
  });
  return energy.total();
}

/// ElementType::elementResults of a Kind: kindGroup per group, stored.
template <class Kind>
void kindElementResults(const ElementBlock& block, const std::vector<double>& params, const Eigen::MatrixX3d& x,
                        int first, int count, int flags, double* energies, double* contributions) {
  constexpr int K = Kind::kVertices;
  const bool write = (flags & (kPassProjection | kPassForce)) != 0;
  const bool force = (flags & kPassForce) != 0;
  const bool energy = (flags & kPassEnergy) != 0;
  double shared[Kind::kRows * K];
  kindSharedCoefficients<Kind>(shared);
  forEachGroup(first, count, [&](int group, int lo, int hi) {
    const int i = group + lo - first;  // the group's first element in the outputs
    double group_energies[projections::kLanes];
    double* out = write ? contributions + 3 * K * i : nullptr;
    if constexpr (ProjectsLanes<Kind>::value) {
      // The buffered pass's contributions are element by element (the gather reads them so).
      double c[3 * Kind::kVertices * projections::kLanes];
      kindGroup<Kind>(block, params, x.data(), x.rows(), shared, group, lo, hi, write, force, group_energies, c);
      if (write)
        for (int l = 0; l < hi - lo; ++l)
          for (int k = 0; k < K; ++k)
            for (int j = 0; j < 3; ++j) out[3 * (K * l + k) + j] = c[contributionAt<Kind>(lo, l, k, j)];
    } else {
      kindGroup<Kind>(block, params, x.data(), x.rows(), shared, group, lo, hi, write, force, group_energies, out);
    }
    if (energy)
      for (int l = 0; l < hi - lo; ++l) energies[i + l] = group_energies[l];
  });
}

/// ElementType::ownedResults of a Kind: kindGroup per group (the same results as kindPass's),
/// each contribution added into `out` only when its vertex is in [lo, hi), each energy stored
/// only when the element's first vertex is.
template <class Kind>
void kindOwnedResults(const ElementBlock& block, const std::vector<double>& params, const Eigen::MatrixX3d& x,
                      int first, int count, int flags, int lo, int hi, Eigen::MatrixX3d* out, double* energies) {
  constexpr int K = Kind::kVertices;
  const bool write = (flags & (kPassProjection | kPassForce)) != 0;
  const bool force = (flags & kPassForce) != 0;
  const bool energy = (flags & kPassEnergy) != 0;
  if (count == 0) return;  // the question whether the type provides it: `out` may be null
  const Eigen::Index n = x.rows();
  const double* xs = x.data();
  double* os = write ? out->data() : nullptr;
  double shared[Kind::kRows * K];
  kindSharedCoefficients<Kind>(shared);
  forEachGroup(first, count, [&](int group, int lane_lo, int lane_hi) {
    double c[3 * Kind::kVertices * projections::kLanes], group_energies[projections::kLanes];
    kindGroup<Kind>(block, params, xs, n, shared, group, lane_lo, lane_hi, write, force, group_energies, c);
    for (int l = 0; l < lane_hi - lane_lo; ++l) {
      const int e = group + lane_lo + l;
      const int* v = block.vertices.data() + K * e;
      if (energy && v[0] >= lo && v[0] < hi) energies[e - first] = group_energies[l];
      if (!write) continue;
      for (int k = 0; k < K; ++k) {
        if (v[k] < lo || v[k] >= hi) continue;
        os[v[k]] += c[contributionAt<Kind>(lane_lo, l, k, 0)];
        os[n + v[k]] += c[contributionAt<Kind>(lane_lo, l, k, 1)];
        os[2 * n + v[k]] += c[contributionAt<Kind>(lane_lo, l, k, 2)];
      }
    }
  });
}

}  // namespace stabint
