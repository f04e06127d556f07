// The exact triangle-triangle intersection counter (tests/triangle_intersections.hpp): CGAL's
// box_intersection_d finds the pairs whose bounding boxes meet, and CGAL::do_intersect on the
// Exact_predicates_inexact_constructions_kernel decides each of them exactly. The kernel's
// predicates are exact for the doubles given, so a vertex lying exactly on another triangle is a
// touch and one 1e-9 off it is not, whatever the rounding of a floating-point test would say.
#include "triangle_intersections.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <string>

namespace stabint::testing {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
// A triangle's bounding box carrying the triangle's row. The boxes are closed (the default
// topology), so triangles that only touch still reach the exact test.
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, int>;

bool shareVertex(const std::array<int, 3>& a, const std::array<int, 3>& b) {
  for (int u : a)
    for (int v : b)
      if (u == v) return true;
  return false;
}

}  // namespace

std::vector<std::pair<int, int>> intersectingTrianglePairList(const Eigen::MatrixX3d& x,
                                                              const std::vector<std::array<int, 3>>& triangles) {
  const int n = static_cast<int>(triangles.size());
  std::vector<Triangle> geometry(triangles.size());
  std::vector<Box> boxes;
  boxes.reserve(triangles.size());
  for (int t = 0; t < n; ++t) {
    Point p[3];
    for (int k = 0; k < 3; ++k) {
      const int v = triangles[t][k];
      if (v < 0 || v >= x.rows())
        throw std::invalid_argument("intersectingTrianglePairList: triangle " + std::to_string(t) + " names vertex " +
                                    std::to_string(v) + " of " + std::to_string(x.rows()));
      p[k] = Point(x(v, 0), x(v, 1), x(v, 2));
    }
    geometry[t] = Triangle(p[0], p[1], p[2]);
    // A triangle of zero area (collinear or repeated vertices, decided exactly) has no inside to
    // pass through; it is left out rather than reported as touching its neighbours' edges.
    if (geometry[t].is_degenerate()) continue;
    // The coordinates are doubles, so the bounding box is exact: no pair is lost to rounding.
    boxes.emplace_back(geometry[t].bbox(), t);
  }

  std::vector<std::pair<int, int>> pairs;
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& a, const Box& b) {
    const int i = std::min(a.info(), b.info()), j = std::max(a.info(), b.info());
    // Triangles that share a vertex always touch in a manifold mesh, so they say nothing; a fold
    // through itself next to a shared vertex still crosses triangles that share none, which are
    // tested.
    if (shareVertex(triangles[static_cast<std::size_t>(i)], triangles[static_cast<std::size_t>(j)])) return;
    if (CGAL::do_intersect(geometry[static_cast<std::size_t>(i)], geometry[static_cast<std::size_t>(j)]))
      pairs.emplace_back(i, j);
  });
  // box_self_intersection_d reports each pair once, in no particular order.
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

int intersectingTrianglePairs(const Eigen::MatrixX3d& x, const std::vector<std::array<int, 3>>& triangles) {
  return static_cast<int>(intersectingTrianglePairList(x, triangles).size());
}

}  // namespace stabint::testing
