// The broad phase's grid (host/contact/box_grid.hpp) against all pairs: a query finds every box
// that overlaps it and nothing else, each once, and pairsInCells every overlapping pair of the
// grid's own boxes once, lower index first; boxes of mixed sizes (a crumpled cloth's swept boxes
// span one to several cells), boxes that touch exactly (closed boxes overlap), queries from
// outside the grid, and a grid of some of the boxes.
#include "contact/box_grid.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <utility>
#include <vector>

namespace stabint {
namespace {

std::vector<Box> randomBoxes(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> where(-1.0, 1.0), size(0.0, 0.15);
  std::vector<Box> boxes(static_cast<std::size_t>(n));
  for (Box& b : boxes) {
    b.lo = Eigen::Vector3d(where(rng), 0.2 * where(rng), where(rng));
    b.hi = b.lo + Eigen::Vector3d(size(rng), size(rng), size(rng)) * (rng() % 8 == 0 ? 4.0 : 1.0);
  }
  // Two that touch at a face and one that touches another at a corner only.
  boxes[1].lo = Eigen::Vector3d(boxes[0].hi.x(), boxes[0].lo.y(), boxes[0].lo.z());
  boxes[1].hi = boxes[1].lo + Eigen::Vector3d(0.1, 0.1, 0.1);
  boxes[2].lo = boxes[1].hi;
  boxes[2].hi = boxes[2].lo + Eigen::Vector3d(0.05, 0.05, 0.05);
  return boxes;
}

TEST(BoxGrid, AQueryFindsEveryOverlappingBoxOnce) {
  const std::vector<Box> boxes = randomBoxes(600, 1);
  std::vector<char> included(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) included[i] = i % 3 == 0 ? 1 : 0;
  for (bool some : {false, true}) {
    const Grid grid(boxes, 0.07, some ? &included : nullptr);
    std::vector<Box> queries = randomBoxes(300, 2);
    queries.push_back(Box{Eigen::Vector3d(5.0, 5.0, 5.0), Eigen::Vector3d(6.0, 6.0, 6.0)});     // far outside
    queries.push_back(Box{Eigen::Vector3d(-3.0, -3.0, -3.0), Eigen::Vector3d(3.0, 3.0, 3.0)});  // around all
    queries.push_back(boxes[1]);  // touching boxes[0] and boxes[2]
    for (const Box& q : queries) {
      std::vector<int> found, expected;
      grid.query(
          q, [](int) { return true; }, [&](int i) { found.push_back(i); });
      for (std::size_t i = 0; i < boxes.size(); ++i)
        if ((!some || included[i]) && q.overlaps(boxes[i])) expected.push_back(static_cast<int>(i));
      std::sort(found.begin(), found.end());
      EXPECT_EQ(found, expected);
    }
  }
}

TEST(BoxGrid, PairsInCellsFindsEveryOverlappingPairOnceInAnyChunking) {
  const std::vector<Box> boxes = randomBoxes(800, 3);
  const Grid grid(boxes, 0.07);
  std::set<std::pair<int, int>> expected;
  for (int i = 0; i < int(boxes.size()); ++i)
    for (int j = i + 1; j < int(boxes.size()); ++j)
      if (boxes[std::size_t(i)].overlaps(boxes[std::size_t(j)]) && (i + j) % 5 != 0) expected.insert({i, j});
  ASSERT_TRUE(expected.count({0, 1}) && expected.count({1, 2}));  // the touching ones
  for (std::size_t chunk : {grid.cells(), std::size_t(1), std::size_t(37)}) {
    std::vector<std::pair<int, int>> found;
    for (std::size_t first = 0; first < grid.cells(); first += chunk)
      grid.pairsInCells(
          first, std::min(grid.cells(), first + chunk), [](int i, int j) { return (i + j) % 5 != 0; },
          [&](int i, int j) { found.emplace_back(i, j); });
    for (const auto& [i, j] : found) EXPECT_LT(i, j);
    const std::set<std::pair<int, int>> unique(found.begin(), found.end());
    EXPECT_EQ(unique.size(), found.size()) << "a pair reported twice";
    EXPECT_EQ(unique, expected);
  }
}

}  // namespace
}  // namespace stabint
