#include "contact/surface_crossings.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>

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
  const std::size_t count = triangles.size();
  std::vector<std::pair<int, int>> crossing;
  if (count < 2) return crossing;
  std::vector<Eigen::Vector3d> lo(count), hi(count);
  double extent = 0.0;
  for (std::size_t t = 0; t < count; ++t) {
    lo[t] = hi[t] = x.row(triangles[t][0]).transpose();
    for (int k = 1; k < 3; ++k) {
      lo[t] = lo[t].cwiseMin(x.row(triangles[t][std::size_t(k)]).transpose());
      hi[t] = hi[t].cwiseMax(x.row(triangles[t][std::size_t(k)]).transpose());
    }
    extent += (hi[t] - lo[t]).maxCoeff();
  }
  if (!(extent > 0.0)) return crossing;  // every triangle a point: none has an inside
  // Cells about a triangle's size, each triangle spanning a few and each cell holding a few; at
  // least a sixteenth of the largest, so that no triangle spans more than 17^3 cells.
  double largest = 0.0;
  for (std::size_t t = 0; t < count; ++t) largest = std::max(largest, (hi[t] - lo[t]).maxCoeff());
  Eigen::Vector3d origin = lo[0];
  for (const Eigen::Vector3d& l : lo) origin = origin.cwiseMin(l);
  const double cell = std::max(extent / double(count), largest / 16.0);
  auto index = [&](double coordinate, double from) {
    return static_cast<std::int64_t>(std::floor((coordinate - from) / cell));
  };
  // (cell key, triangle), sorted by key: the triangles of each cell together, in a fixed order.
  std::vector<std::pair<std::array<std::int64_t, 3>, int>> entries;
  for (std::size_t t = 0; t < count; ++t) {
    std::array<std::int64_t, 3> first, last;
    for (int c = 0; c < 3; ++c) {
      first[std::size_t(c)] = index(lo[t][c], origin[c]);
      last[std::size_t(c)] = index(hi[t][c], origin[c]);
    }
    for (std::int64_t i = first[0]; i <= last[0]; ++i)
      for (std::int64_t j = first[1]; j <= last[1]; ++j)
        for (std::int64_t k = first[2]; k <= last[2]; ++k) entries.push_back({{i, j, k}, static_cast<int>(t)});
  }
  std::sort(entries.begin(), entries.end());
  std::vector<std::pair<int, int>> candidates;
  for (std::size_t begin = 0; begin < entries.size();) {
    std::size_t end = begin;
    while (end < entries.size() && entries[end].first == entries[begin].first) ++end;
    for (std::size_t m = begin; m < end; ++m)
      for (std::size_t n = m + 1; n < end; ++n) {
        const int a = std::min(entries[m].second, entries[n].second),
                  b = std::max(entries[m].second, entries[n].second);
        const std::size_t ua = std::size_t(a), ub = std::size_t(b);
        if ((lo[ua].array() > hi[ub].array()).any() || (lo[ub].array() > hi[ua].array()).any()) continue;
        if (shareParticle(triangles[ua], triangles[ub])) continue;
        candidates.emplace_back(a, b);
      }
    begin = end;
  }
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  auto corners = [&](int t) {
    std::array<Eigen::Vector3d, 3> p;
    for (int k = 0; k < 3; ++k) p[std::size_t(k)] = x.row(triangles[std::size_t(t)][std::size_t(k)]).transpose();
    return p;
  };
  for (const auto& [a, b] : candidates)
    if (cross(corners(a), corners(b))) crossing.emplace_back(a, b);
  return crossing;
}

}  // namespace stabint
