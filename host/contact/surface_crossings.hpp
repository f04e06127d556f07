#pragma once
// Where a scene's surface crosses itself (docs/method.md, "Self-contact", "A start free of
// crossings"): self-contact keeps a crossing-free state so and cannot undo a crossing, so a scene
// (or a new state) that starts with one is refused before anything steps.
#include <Eigen/Core>

#include <array>
#include <utility>
#include <vector>

namespace stabint {

/// The pairs (i < j, ascending) of `triangles` (particle rows of `x`) that cross: a side of one
/// passes through the inside of the other, both strictly: a point within 1e-10 (relative) of a
/// plane or a side lies on it, which is a touch, not a crossing. Triangles that share a particle
/// are not tested (neighbours of a mesh always touch), and triangles in one plane do not cross.
/// Found through the broad phase's grid over the triangles' bounding boxes (box_grid.hpp).
std::vector<std::pair<int, int>> crossingTriangles(const Eigen::MatrixX3d& x,
                                                   const std::vector<std::array<int, 3>>& triangles);

}  // namespace stabint
