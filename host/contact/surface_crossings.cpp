#include "contact/surface_crossings.hpp"

#include "contact/box_grid.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace stabint {

namespace {

// Orientations within this fraction of the product of the lengths involved are round-off: a point
// that near a plane lies in it (two triangles of one flat sheet, turned by rounded sines, are in
// one plane, not crossing).
constexpr double kFlat = 1e-10;

// The sign of (b - a) x (c - a) . (p - a) (positive: p on the side triangle abc's normal points
// to), 0 within round-off.
int orient(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& p) {
  const Eigen::Vector3d u = b - a, v = c - a, w = p - a;
  const double value = u.cross(v).dot(w);
  if (std::abs(value) <= kFlat * u.norm() * v.norm() * w.norm()) return 0;
  return value > 0.0 ? 1 : -1;
}

// The segment pq passes through the inside of triangle abc: its ends strictly on opposite sides
// of the plane, and the line through them strictly inside the three edges.
bool segmentCrosses(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const int sp = orient(a, b, c, p), sq = orient(a, b, c, q);
  if (sp == 0 || sq == 0 || sp == sq) return false;
  const int u = orient(p, q, a, b), v = orient(p, q, b, c), w = orient(p, q, c, a);
  return u != 0 && u == v && v == w;
}

bool cross(const std::array<Eigen::Vector3d, 3>& s, const std::array<Eigen::Vector3d, 3>& t) {
  for (int k = 0; k < 3; ++k) {
    if (segmentCrosses(s[k], s[(k + 1) % 3], t[0], t[1], t[2])) return true;
    if (segmentCrosses(t[k], t[(k + 1) % 3], s[0], s[1], s[2])) return true;
  }
  return false;
}

bool shareParticle(const std::array<int, 3>& a, const std::array<int, 3>& b) {
  for (int u : a)
    for (int v : b)
      if (u == v) return true;
  return false;
}

}  // namespace

std::vector<std::pair<int, int>> crossingTriangles(const Eigen::MatrixX3d& x,
                                                   const std::vector<std::array<int, 3>>& triangles) {
  std::vector<std::pair<int, int>> crossing;
  if (triangles.size() < 2) return crossing;
  auto corners = [&](std::size_t t) {
    std::array<Eigen::Vector3d, 3> p;
    for (std::size_t k = 0; k < 3; ++k) p[k] = x.row(triangles[t][k]).transpose();
    return p;
  };
  std::vector<Box> boxes(triangles.size());
  double extent = 0.0;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const std::array<Eigen::Vector3d, 3> p = corners(t);
    boxes[t] = {p[0].cwiseMin(p[1]).cwiseMin(p[2]), p[0].cwiseMax(p[1]).cwiseMax(p[2])};
    extent += (boxes[t].hi - boxes[t].lo).maxCoeff();
  }
  if (!(extent > 0.0)) return crossing;  // every triangle a point: none has an inside
  // Cells about a triangle's size: each triangle spans a few, each cell holds a few.
  const Grid grid(boxes, extent / double(triangles.size()));
  for (std::size_t a = 0; a < triangles.size(); ++a)
    grid.query(
        boxes[a], [&](int b) { return std::size_t(b) > a && !shareParticle(triangles[a], triangles[std::size_t(b)]); },
        [&](int b) {
          if (cross(corners(a), corners(std::size_t(b)))) crossing.emplace_back(int(a), b);
        });
  std::sort(crossing.begin(), crossing.end());
  return crossing;
}

}  // namespace stabint
