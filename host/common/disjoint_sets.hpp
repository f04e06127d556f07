#pragma once
// Union-find over 0..n-1 (path halving): the bodies a scene's elements connect
// (scene/connected_bodies.hpp) and self-contact's tet bodies and impact zones.
#include <cstddef>
#include <numeric>
#include <vector>

namespace stabint {

class DisjointSets {
 public:
  explicit DisjointSets(int n) : parent_(static_cast<std::size_t>(n)) { std::iota(parent_.begin(), parent_.end(), 0); }
  /// The root of i's set.
  int find(int i) {
    while (parent_[std::size_t(i)] != i) i = parent_[std::size_t(i)] = parent_[std::size_t(parent_[std::size_t(i)])];
    return i;
  }
  /// Joins a's set to b's: the root of b's set becomes the root of both.
  void join(int a, int b) {
    const int root = find(b);
    parent_[std::size_t(find(a))] = root;
  }

 private:
  std::vector<int> parent_;
};

}  // namespace stabint
