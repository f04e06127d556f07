#pragma once
// Axis-aligned boxes in a uniform grid: self-contact's broad phase (self_contact.cpp) and the
// check for a surface that crosses itself (surface_crossings.cpp).
#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace stabint {

struct Box {
  Eigen::Vector3d lo, hi;
  bool overlaps(const Box& o) const { return (lo.array() <= o.hi.array()).all() && (o.lo.array() <= hi.array()).all(); }
};

// A uniform grid of boxes over their bounding box, dense: each box in every cell it covers, the
// cells' lists one array (counting sort), each list in box order.
class Grid {
 public:
  Grid() = default;  // no boxes
  // The boxes whose `included` flag is set (all without flags).
  Grid(const std::vector<Box>& boxes, double cell, const std::vector<char>* included = nullptr) {
    bool any = false;
    Eigen::Vector3d hi = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      if (included && !(*included)[i]) continue;
      lo_ = any ? lo_.cwiseMin(boxes[i].lo) : boxes[i].lo;
      hi = any ? hi.cwiseMax(boxes[i].hi) : boxes[i].hi;
      any = true;
    }
    if (!any) return;
    // At most about 2^21 cells: coarser cells for a scene spread far.
    const Eigen::Vector3d span = hi - lo_;
    constexpr double kMaxCells = double(1 << 21);
    const double cells = ((span / cell).array() + 1.0).prod();
    if (cells > kMaxCells) cell *= std::cbrt(cells / kMaxCells) * 1.01;
    cell_ = cell;
    for (int c = 0; c < 3; ++c) dims_[c] = static_cast<int>(span[c] / cell_) + 1;
    starts_.assign(std::size_t(dims_[0]) * std::size_t(dims_[1]) * std::size_t(dims_[2]) + 1, 0);
    for (std::size_t i = 0; i < boxes.size(); ++i)
      if (!included || (*included)[i]) forCells(boxes[i], [&](std::size_t key) { ++starts_[key + 1]; });
    for (std::size_t k = 1; k < starts_.size(); ++k) starts_[k] += starts_[k - 1];
    entries_.resize(std::size_t(starts_.back()));
    std::vector<int> fill(starts_.begin(), starts_.end() - 1);
    for (std::size_t i = 0; i < boxes.size(); ++i)
      if (!included || (*included)[i])
        forCells(boxes[i], [&](std::size_t key) {
          entries_[std::size_t(fill[key]++)] = {boxes[i], static_cast<int>(i)};
        });
  }
  // Every box overlapping `b` that `wanted(index)` accepts, each once: a pair is reported in the
  // cell of its overlap's lowest corner only.
  template <typename Wanted, typename F>
  void query(const Box& b, Wanted&& wanted, F&& f) const {
    if (entries_.empty()) return;
    forCells(b, [&](std::size_t key) {
      for (int e = starts_[key]; e < starts_[key + 1]; ++e) {
        const Entry& o = entries_[std::size_t(e)];
        if (wanted(o.index) && b.overlaps(o.box) && cellOf(b.lo.cwiseMax(o.box.lo)) == key) f(o.index);
      }
    });
  }

 private:
  struct Entry {
    Box box;  // a copy: a cell's boxes are read in one run
    int index;
  };
  template <typename F>
  void forCells(const Box& b, F&& f) const {
    int lo[3], hi[3];
    for (int c = 0; c < 3; ++c) {
      lo[c] = coordinate(b.lo[c], c);
      hi[c] = coordinate(b.hi[c], c);
    }
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) f(key(i, j, k));
  }
  // A point outside the grid's box (a query's) falls in its nearest cell.
  int coordinate(double x, int c) const {
    return std::clamp(static_cast<int>(std::floor((x - lo_[c]) / cell_)), 0, dims_[c] - 1);
  }
  std::size_t cellOf(const Eigen::Vector3d& p) const {
    return key(coordinate(p[0], 0), coordinate(p[1], 1), coordinate(p[2], 2));
  }
  std::size_t key(int i, int j, int k) const {
    return std::size_t(i) + std::size_t(dims_[0]) * (std::size_t(j) + std::size_t(dims_[1]) * std::size_t(k));
  }
  Eigen::Vector3d lo_ = Eigen::Vector3d::Zero();
  double cell_ = 1.0;
  int dims_[3] = {1, 1, 1};
  std::vector<int> starts_;
  std::vector<Entry> entries_;
};

}  // namespace stabint
