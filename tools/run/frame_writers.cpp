#include "frame_writers.hpp"

#include <algorithm>
#include <map>

namespace stabint_run {

std::vector<std::array<int, 3>> tetBoundary(const std::vector<stabint::Tet>& tets) {
  std::map<std::array<int, 3>, std::pair<int, std::array<int, 3>>> faces;
  for (const stabint::Tet& t : tets) {
    const auto& v = t.vertices;
    const std::array<std::array<int, 3>, 4> local = {
        {{v[0], v[2], v[1]}, {v[0], v[1], v[3]}, {v[0], v[3], v[2]}, {v[1], v[2], v[3]}}};
    for (const auto& f : local) {
      std::array<int, 3> key = f;
      std::sort(key.begin(), key.end());
      auto& entry = faces[key];
      ++entry.first;
      entry.second = f;
    }
  }
  std::vector<std::array<int, 3>> boundary;
  for (const auto& [key, entry] : faces) {
    if (entry.first == 1) boundary.push_back(entry.second);
  }
  return boundary;
}

}  // namespace stabint_run
