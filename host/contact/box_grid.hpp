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
// cells' lists one array (counting sort), each list in box order. A pair of overlapping boxes is
// reported once, in the cell of its overlap's lowest corner: the cell whose coordinates are the
// larger of the two boxes' first cells (a cell's coordinate grows with the position), integers
// each entry carries.
class Grid {
 public:
  Grid() = default;  // no boxes
  // The boxes whose `included` flag is set (all without flags).
  Grid(const std::vector<Box>& boxes, double cell, const std::vector<char>* included = nullptr) {
    bool any = false;
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      if (included && !(*included)[i]) continue;
      bounds_.lo = any ? bounds_.lo.cwiseMin(boxes[i].lo) : boxes[i].lo;
      bounds_.hi = any ? bounds_.hi.cwiseMax(boxes[i].hi) : boxes[i].hi;
      any = true;
    }
    if (!any) return;
    // At most about 2^21 cells: coarser cells for a scene spread far.
    const Eigen::Vector3d span = bounds_.hi - bounds_.lo;
    constexpr double kMaxCells = double(1 << 21);
    const double cells = ((span / cell).array() + 1.0).prod();
    if (cells > kMaxCells) cell *= std::cbrt(cells / kMaxCells) * 1.01;
    cell_ = cell;
    for (int c = 0; c < 3; ++c) dims_[c] = static_cast<int>(span[c] / cell_) + 1;
    starts_.assign(std::size_t(dims_[0]) * std::size_t(dims_[1]) * std::size_t(dims_[2]) + 1, 0);
    // Each box's cells, computed once for the count and the fill.
    std::vector<CellRange> ranges(boxes.size());
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      if (included && !(*included)[i]) continue;
      ranges[i] = cellsOf(boxes[i]);
      forCells(ranges[i], [&](std::size_t key) { ++starts_[key + 1]; });
    }
    for (std::size_t k = 1; k < starts_.size(); ++k) starts_[k] += starts_[k - 1];
    entries_.resize(std::size_t(starts_.back()));
    std::vector<int> fill(starts_.begin(), starts_.end() - 1);
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      if (included && !(*included)[i]) continue;
      const CellRange& r = ranges[i];
      const Entry entry{boxes[i], static_cast<int>(i), {r.lo[0], r.lo[1], r.lo[2]}};
      forCells(r, [&](std::size_t key) { entries_[std::size_t(fill[key]++)] = entry; });
    }
  }

  // Every box overlapping `b` that `wanted(index)` accepts, each once, cell by cell in key order
  // and in box order within a cell.
  template <typename Wanted, typename F>
  void query(const Box& b, Wanted&& wanted, F&& f) const {
    if (entries_.empty() || !b.overlaps(bounds_)) return;  // (a grid of a few boxes meets most queries so)
    const CellRange r = cellsOf(b);
    for (int k = r.lo[2]; k <= r.hi[2]; ++k)
      for (int j = r.lo[1]; j <= r.hi[1]; ++j)
        for (int i = r.lo[0]; i <= r.hi[0]; ++i) {
          const std::size_t cell = key(i, j, k);
          for (int e = starts_[cell]; e < starts_[cell + 1]; ++e) {
            const Entry& o = entries_[std::size_t(e)];
            if (b.overlaps(o.box) && std::max(r.lo[0], o.first_cell[0]) == i &&
                std::max(r.lo[1], o.first_cell[1]) == j && std::max(r.lo[2], o.first_cell[2]) == k && wanted(o.index))
              f(o.index);
          }
        }
  }

  // Every pair of the grid's own boxes (a < b) that overlap and `wanted(a, b)` accepts, each once,
  // from the cells [first, last) in key order: each cell's pairs of entries once, where a query
  // per box meets each pair twice.
  template <typename Wanted, typename F>
  void pairsInCells(std::size_t first, std::size_t last, Wanted&& wanted, F&& f) const {
    for (std::size_t cell = first; cell < last; ++cell) {
      const int begin = starts_[cell], end = starts_[cell + 1];
      if (end - begin < 2) continue;
      const int at[3] = {int(cell % std::size_t(dims_[0])), int(cell / std::size_t(dims_[0]) % std::size_t(dims_[1])),
                         int(cell / (std::size_t(dims_[0]) * std::size_t(dims_[1])))};
      for (int a = begin; a < end; ++a) {
        const Entry& p = entries_[std::size_t(a)];
        for (int b = a + 1; b < end; ++b) {
          const Entry& o = entries_[std::size_t(b)];
          if (p.box.overlaps(o.box) && std::max(p.first_cell[0], o.first_cell[0]) == at[0] &&
              std::max(p.first_cell[1], o.first_cell[1]) == at[1] &&
              std::max(p.first_cell[2], o.first_cell[2]) == at[2] && wanted(p.index, o.index))
            f(p.index, o.index);
        }
      }
    }
  }
  // The number of cells (pairsInCells' range).
  std::size_t cells() const { return starts_.empty() ? 0 : starts_.size() - 1; }

 private:
  struct Entry {
    Box box;  // a copy: a cell's boxes are read in one run
    int index;
    int first_cell[3];  // the cell coordinates of box.lo
  };
  struct CellRange {
    int lo[3] = {0, 0, 0}, hi[3] = {-1, -1, -1};
  };
  CellRange cellsOf(const Box& b) const {
    CellRange r;
    for (int c = 0; c < 3; ++c) {
      r.lo[c] = coordinate(b.lo[c], c);
      r.hi[c] = coordinate(b.hi[c], c);
    }
    return r;
  }
  template <typename F>
  void forCells(const CellRange& r, F&& f) const {
    for (int k = r.lo[2]; k <= r.hi[2]; ++k)
      for (int j = r.lo[1]; j <= r.hi[1]; ++j)
        for (int i = r.lo[0]; i <= r.hi[0]; ++i) f(key(i, j, k));
  }
  // A point outside the grid's box (a query's) falls in its nearest cell.
  int coordinate(double x, int c) const {
    return std::clamp(static_cast<int>(std::floor((x - bounds_.lo[c]) / cell_)), 0, dims_[c] - 1);
  }
  std::size_t key(int i, int j, int k) const {
    return std::size_t(i) + std::size_t(dims_[0]) * (std::size_t(j) + std::size_t(dims_[1]) * std::size_t(k));
  }
  Box bounds_{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};  // of the boxes it holds
  double cell_ = 1.0;
  int dims_[3] = {1, 1, 1};
  std::vector<int> starts_;
  std::vector<Entry> entries_;
};

}  // namespace stabint
