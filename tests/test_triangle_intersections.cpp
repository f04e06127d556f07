// The exact triangle-triangle intersection counter of the self-contact tests
// (tests/triangle_intersections.hpp): pairs whose answer is known by construction (piercing,
// touching exactly, 1e-9 apart, shared vertices, degenerate triangles), grids flat, spiked and
// folded over onto themselves, and random soups against an all-pairs loop without the broad phase.
#include "triangle_intersections.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

namespace stabint {
namespace {

using testing::intersectingTrianglePairList;
using testing::intersectingTrianglePairs;

struct Mesh {
  Eigen::MatrixX3d x;
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> square_row;  // per triangle: the row of the grid square it halves
};

Mesh twoTriangles(const std::array<Eigen::Vector3d, 6>& p) {
  Mesh m;
  m.x.resize(6, 3);
  for (int k = 0; k < 6; ++k) m.x.row(k) = p[k].transpose();
  m.triangles = {{0, 1, 2}, {3, 4, 5}};
  return m;
}

// A flat triangle in the tilted plane z = y (normal (0, -1, 1)), and a second one whose first
// vertex lies exactly on the first one's inside at p = (0.25, 0.5, 0.5) (barycentric 1/4, 1/4,
// 1/2, all coordinates exact in binary) and whose other two lie on the normal's side, moved by
// `offset`.
Mesh touchingPair(const Eigen::Vector3d& offset) {
  const Eigen::Vector3d p(0.25, 0.5, 0.5);
  return twoTriangles({Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(1.0, 0.0, 0.0), Eigen::Vector3d(0.0, 1.0, 1.0),
                       p + offset, Eigen::Vector3d(0.25, -0.5, 1.5) + offset,
                       Eigen::Vector3d(0.5, -0.5, 1.5) + offset});
}

// An n x (rows - 1) grid of squares of side h = 1/n, two triangles per square; `at(i, r)` places
// the vertex of column i, row r.
template <class At>
Mesh grid(int n, int rows, At at) {
  Mesh m;
  m.x.resize((n + 1) * rows, 3);
  auto index = [&](int i, int r) { return i * rows + r; };
  for (int i = 0; i <= n; ++i)
    for (int r = 0; r < rows; ++r) m.x.row(index(i, r)) = at(i, r).transpose();
  for (int i = 0; i < n; ++i)
    for (int r = 0; r + 1 < rows; ++r) {
      const int a = index(i, r), b = index(i + 1, r), c = index(i + 1, r + 1), d = index(i, r + 1);
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
      m.square_row.push_back(r);
      m.square_row.push_back(r);
    }
  return m;
}

// The flat n x n grid in the x-z plane, vertex (i, j) at (i h, 0, j h).
Mesh flatGrid(int n) {
  const double h = 1.0 / n;
  return grid(n, n + 1, [h](int i, int j) { return Eigen::Vector3d(i * h, 0.0, j * h); });
}

// The flat grid doubled and folded over onto itself: rows 0..n are the lower layer (y = 0), a
// vertical strip of squares at z = 1 rises from row n to row n + 1 at y = `height`, and rows
// n + 1..2n + 1 are the upper layer, row r exactly above row 2n + 1 - r of the lower one. Square
// rows below n are the lower layer, n the strip, above n the upper layer.
Mesh foldedGrid(int n, double height) {
  const double h = 1.0 / n;
  return grid(n, 2 * n + 2, [=](int i, int r) {
    return r <= n ? Eigen::Vector3d(i * h, 0.0, r * h) : Eigen::Vector3d(i * h, height, (2 * n + 1 - r) * h);
  });
}

bool contains(const std::array<int, 3>& t, int v) { return t[0] == v || t[1] == v || t[2] == v; }

TEST(TriangleIntersections, PiercingPairIntersects) {
  // Moved half a unit against the normal, the second triangle's edges from its first vertex cross
  // the plane at p, inside the first triangle.
  const Mesh m = touchingPair(Eigen::Vector3d(0.0, 0.5, -0.5));
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), 1);
  EXPECT_EQ(intersectingTrianglePairList(m.x, m.triangles), (std::vector<std::pair<int, int>>{{0, 1}}));
}

TEST(TriangleIntersections, ExactTouchCountsAndAGapOf1e9DoesNot) {
  // A vertex lying exactly on the other triangle touches it; 1e-9 off the plane along the normal
  // (away from the rest of its triangle) they are apart, 1e-9 the other way the triangle pierces.
  const Eigen::Vector3d normal = Eigen::Vector3d(0.0, -1.0, 1.0).normalized();
  const Mesh touching = touchingPair(Eigen::Vector3d::Zero());
  EXPECT_EQ(intersectingTrianglePairs(touching.x, touching.triangles), 1);
  const Mesh apart = touchingPair(1e-9 * normal);
  EXPECT_EQ(intersectingTrianglePairs(apart.x, apart.triangles), 0);
  const Mesh through = touchingPair(-1e-9 * normal);
  EXPECT_EQ(intersectingTrianglePairs(through.x, through.triangles), 1);
}

TEST(TriangleIntersections, PairsSharingAVertexAreSkipped) {
  // Two triangles meeting only at vertex 0: skipped as one vertex, counted as two copies of it.
  Mesh m;
  m.x.resize(6, 3);
  m.x << 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,  //
      0.0, 1.0, 0.0, -1.0, 1.0, 0.0, 0.0, 0.0, 0.0;
  m.triangles = {{0, 1, 2}, {0, 3, 4}};
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), 0);
  m.triangles = {{0, 1, 2}, {5, 3, 4}};
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), 1);
  // Skipped even where the second one folds through the first next to the shared vertex (its far
  // edge crosses y = 0 at (0.375, 0, 0.375), inside the first): in a mesh, the fold's neighbours
  // that share no vertex report it.
  m.x.row(3) << 0.5, -1.0, 0.25;
  m.x.row(4) << 0.25, 1.0, 0.5;
  m.triangles = {{0, 1, 2}, {0, 3, 4}};
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), 0);
  m.triangles = {{0, 1, 2}, {5, 3, 4}};
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), 1);
}

TEST(TriangleIntersections, DegenerateTrianglesAreSkipped) {
  // Three collinear points on a segment through the flat triangle's inside: no area, not counted;
  // moved off the line, the same triangle pierces.
  Mesh m;
  m.x.resize(6, 3);
  m.x << 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,  //
      0.25, -0.5, 0.25, 0.25, 0.0, 0.25, 0.25, 0.5, 0.25;
  m.triangles = {{0, 1, 2}, {3, 4, 5}};
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), 0);
  m.x.row(5) << 0.5, 0.5, 0.25;
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), 1);
  m.triangles = {{0, 1, 2}, {3, 3, 5}};  // a repeated vertex: no area either
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), 0);
}

TEST(TriangleIntersections, VertexIndexOutsideThePositionsThrows) {
  const Mesh m = touchingPair(Eigen::Vector3d::Zero());
  EXPECT_THROW(intersectingTrianglePairs(m.x, {{0, 1, 6}}), std::invalid_argument);
  EXPECT_THROW(intersectingTrianglePairs(m.x, {{-1, 1, 2}}), std::invalid_argument);
}

TEST(TriangleIntersections, FlatGridHasNone) {
  const Mesh m = flatGrid(10);
  ASSERT_EQ(m.triangles.size(), 200u);
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), 0);
}

TEST(TriangleIntersections, SpikeOfAFlatGridCrossesNothing) {
  // An interior vertex pushed 1 m down: its triangles meet the plane only along its ring, whose
  // triangles all share a vertex with them, so a flat grid cannot pierce itself this way (the
  // folded grid below can).
  Mesh m = flatGrid(10);
  m.x(5 * 11 + 5, 1) -= 1.0;
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), 0);
}

TEST(TriangleIntersections, FoldedGridLayersApartHaveNone) {
  // The upper layer lies exactly 0.01 above the lower one, the strip touches each only at their
  // shared rows.
  const Mesh m = foldedGrid(10, 0.01);
  ASSERT_EQ(m.triangles.size(), 420u);
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), 0);
}

TEST(TriangleIntersections, SpikeThroughTheLowerLayerPiercesFarTriangles) {
  // An interior vertex of the upper layer (column 5, row 16, above the lower layer's row 5)
  // pushed 1 m down: its six triangles pass through the lower layer, eleven rows of the mesh away,
  // and nothing else intersects.
  Mesh m = foldedGrid(10, 0.01);
  const int tip = 5 * 22 + 16;
  m.x(tip, 1) -= 1.0;
  const std::vector<std::pair<int, int>> pairs = intersectingTrianglePairList(m.x, m.triangles);
  EXPECT_GT(pairs.size(), 0u);
  for (const auto& [i, j] : pairs) {
    const bool i_lower = m.square_row[i] < 10, j_lower = m.square_row[j] < 10;
    EXPECT_TRUE(i_lower ? contains(m.triangles[j], tip) : j_lower && contains(m.triangles[i], tip)) << i << " " << j;
  }
}

TEST(TriangleIntersections, FoldedGridLayersCrossingAreFound) {
  // The upper layer's free edge pushed down by 0.02 (the layer tilting linearly from 0.01 above
  // the lower one at the fold to 0.01 below at its free edge): the two layers cross in between,
  // and every pair found is one triangle of each layer.
  Mesh m = foldedGrid(10, 0.01);
  for (int i = 0; i <= 10; ++i)
    for (int r = 11; r < 22; ++r) m.x(i * 22 + r, 1) -= 0.02 * (r - 11) / 10.0;
  const std::vector<std::pair<int, int>> pairs = intersectingTrianglePairList(m.x, m.triangles);
  EXPECT_GT(pairs.size(), 0u);
  for (const auto& [i, j] : pairs) {
    const int lower = std::min(m.square_row[i], m.square_row[j]), upper = std::max(m.square_row[i], m.square_row[j]);
    EXPECT_TRUE(lower < 10 && upper > 10) << i << " " << j;
  }
}

// Random soups of small triangles in the unit box; every fourth triangle reuses a vertex of the
// one before, so shared vertices are skipped in both counts. With `snap` > 0 the coordinates are
// snapped to multiples of it (exact in binary for 1/32), which makes exact touches, coplanar pairs,
// boxes meeting at a face and degenerate triangles common.
Mesh soup(int count, double size, double snap, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0), jitter(-0.5 * size, 0.5 * size);
  Mesh m;
  m.x.resize(3 * count, 3);
  for (int t = 0; t < count; ++t) {
    const Eigen::Vector3d center(unit(rng), unit(rng), unit(rng));
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d p = center + Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng));
      if (snap > 0.0) p = (p / snap).array().round().matrix() * snap;
      m.x.row(3 * t + k) = p.transpose();
    }
    m.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
    if (t % 4 == 3) m.triangles.back()[0] = 3 * (t - 1) + 1;
  }
  return m;
}

// All pairs, no broad phase: the reference the box-intersection count must match.
int bruteForcePairs(const Mesh& m) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  std::vector<Kernel::Triangle_3> t;
  for (const auto& tri : m.triangles) {
    auto point = [&](int v) { return Kernel::Point_3(m.x(v, 0), m.x(v, 1), m.x(v, 2)); };
    t.emplace_back(point(tri[0]), point(tri[1]), point(tri[2]));
  }
  int found = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i].is_degenerate()) continue;
    for (std::size_t j = i + 1; j < t.size(); ++j) {
      bool shared = false;
      for (int u : m.triangles[i])
        for (int v : m.triangles[j]) shared = shared || u == v;
      if (!shared && !t[j].is_degenerate() && CGAL::do_intersect(t[i], t[j])) ++found;
    }
  }
  return found;
}

TEST(TriangleIntersections, RandomSoupMatchesAllPairs) {
  const Mesh m = soup(2000, 0.08, 0.0, 11);
  const int expected = bruteForcePairs(m);
  // Dense enough that the comparison is not about zero.
  EXPECT_GT(expected, 100);
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), expected);
}

TEST(TriangleIntersections, SnappedSoupMatchesAllPairs) {
  const Mesh m = soup(2000, 0.08, 1.0 / 32.0, 12);
  const int expected = bruteForcePairs(m);
  EXPECT_GT(expected, 100);
  EXPECT_EQ(intersectingTrianglePairs(m.x, m.triangles), expected);
}

}  // namespace
}  // namespace stabint
