#include "scene/connected_bodies.hpp"

#include "common/disjoint_sets.hpp"

#include <array>
#include <cstddef>

namespace stabint {

namespace {

template <std::size_t K>
void joinAll(DisjointSets& sets, const std::array<int, K>& vertices) {
  for (std::size_t k = 1; k < vertices.size(); ++k) sets.join(vertices[k], vertices[0]);
}

// The sets' classes of the particles `member` admits, each ascending, in the order of their first
// particle.
template <class Member>
std::vector<std::vector<int>> classes(DisjointSets& sets, int n, Member member) {
  std::vector<int> body_of_root(static_cast<std::size_t>(n), -1);
  std::vector<std::vector<int>> bodies;
  for (int i = 0; i < n; ++i) {
    if (!member(i)) continue;
    int& b = body_of_root[std::size_t(sets.find(i))];
    if (b < 0) {
      b = static_cast<int>(bodies.size());
      bodies.emplace_back();
    }
    bodies[std::size_t(b)].push_back(i);
  }
  return bodies;
}

}  // namespace

std::vector<std::vector<int>> connectedBodies(const Scene& scene) {
  const int n = scene.numParticles();
  DisjointSets sets(n);
  for (const Spring& s : scene.springs) sets.join(s.b, s.a);
  for (const Tet& t : scene.tets) joinAll(sets, t.vertices);
  for (const TriangleStrain& t : scene.triangle_strains) joinAll(sets, t.vertices);
  for (const BendingHinge& h : scene.bending_hinges) joinAll(sets, h.vertices);
  return classes(sets, n, [](int) { return true; });
}

std::vector<std::vector<int>> tetBodies(const Scene& scene) {
  const int n = scene.numParticles();
  DisjointSets sets(n);
  std::vector<char> in_tet(static_cast<std::size_t>(n), 0);
  for (const Tet& t : scene.tets) {
    joinAll(sets, t.vertices);
    for (int v : t.vertices) in_tet[std::size_t(v)] = 1;
  }
  return classes(sets, n, [&](int i) { return in_tet[std::size_t(i)] != 0; });
}

}  // namespace stabint
