#pragma once
// An exact triangle-triangle intersection counter for the tests of self-contact: which triangles
// of a mesh pass through (or touch) one another, decided with CGAL's exact predicates
// (tests/triangle_intersections.cpp), so that a test's verdict never depends on a tolerance.
// Only the test executables that use it link CGAL; the library itself never sees it.
#include <Eigen/Core>

#include <array>
#include <utility>
#include <vector>

namespace stabint::testing {

/// The unordered pairs (i, j), i < j, sorted, of rows of `triangles` (vertex indices into the
/// rows of `x`) that share no vertex and intersect, touching included, decided exactly.
/// Pairs that share a vertex index are skipped: in a manifold mesh they always touch, and a fold
/// through itself next to a shared vertex is still caught by the neighbouring pairs that share
/// none. Degenerate triangles (zero area, exactly) are skipped too. Throws std::invalid_argument
/// when a vertex index is outside the rows of `x`.
std::vector<std::pair<int, int>> intersectingTrianglePairList(const Eigen::MatrixX3d& x,
                                                              const std::vector<std::array<int, 3>>& triangles);

/// The number of pairs intersectingTrianglePairList reports.
int intersectingTrianglePairs(const Eigen::MatrixX3d& x, const std::vector<std::array<int, 3>>& triangles);

}  // namespace stabint::testing
