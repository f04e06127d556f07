#include "scene/connected_bodies.hpp"

#include "common/disjoint_sets.hpp"

namespace stabint {

std::vector<std::vector<int>> connectedBodies(const Scene& scene) {
  const int n = scene.numParticles();
  DisjointSets sets(n);
  for (const Spring& s : scene.springs) sets.join(s.b, s.a);
  const auto joinAll = [&](const auto& vertices) {
    for (std::size_t k = 1; k < vertices.size(); ++k) sets.join(vertices[k], vertices[0]);
  };
  for (const Tet& t : scene.tets) joinAll(t.vertices);
  for (const TriangleStrain& t : scene.triangle_strains) joinAll(t.vertices);
  for (const BendingHinge& h : scene.bending_hinges) joinAll(h.vertices);
  std::vector<int> body_of_root(static_cast<std::size_t>(n), -1);
  std::vector<std::vector<int>> bodies;
  for (int i = 0; i < n; ++i) {
    int& b = body_of_root[std::size_t(sets.find(i))];
    if (b < 0) {
      b = static_cast<int>(bodies.size());
      bodies.emplace_back();
    }
    bodies[std::size_t(b)].push_back(i);
  }
  return bodies;
}

}  // namespace stabint
