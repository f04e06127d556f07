#include "io/mesh_scene.hpp"

#include <cmath>
#include <filesystem>
#include <numeric>

namespace stabint::io {

// A file name is bytes (Latin-1 names exist); the scene name must be text that a scene file can hold.
std::string sceneNameFromPath(const std::string& path) { return validUtf8(std::filesystem::path(path).stem().string()); }

Scene sceneFromMesh(const std::string& name, const Eigen::MatrixX3d& vertices, Eigen::VectorXd masses) {
  Scene s;
  s.name = name;
  s.rest_positions = vertices;
  s.positions = vertices;
  s.velocities = Eigen::MatrixX3d::Zero(vertices.rows(), 3);
  s.masses = std::move(masses);
  Body body{name, std::vector<int>(vertices.rows()), 0.0};
  std::iota(body.particles.begin(), body.particles.end(), 0);
  s.bodies.push_back(std::move(body));
  return s;
}

int parseVertexIndex(const TextReader& reader, const std::string& token, int base, int num_vertices,
                     const std::string& element) {
  const int written = reader.parseInt(token, element + " vertex index");
  const long index = static_cast<long>(written) - base;
  if (index < 0 || index >= num_vertices) {
    reader.fail(element + ": vertex index " + std::to_string(written) + " out of range [" + std::to_string(base) +
                ", " + std::to_string(static_cast<long>(num_vertices) + base) + ")");
  }
  return static_cast<int>(index);
}

namespace {

// "Zero" relative to the tet's own size, so round-off on a flat tet does not pass as a sliver
// with a random sign.
bool isFlat(const Eigen::MatrixX3d& x, const std::array<int, 4>& v, double volume) {
  double longest = 0.0;
  for (int a = 0; a < 4; ++a) {
    for (int b = a + 1; b < 4; ++b) longest = std::max(longest, (x.row(v[a]) - x.row(v[b])).norm());
  }
  return std::abs(volume) <= 1e-12 * longest * longest * longest;
}

std::string tetName(const TetRecord& t) { return "tet " + std::to_string(t.id); }

}  // namespace

void orientTets(const std::string& file, const Eigen::MatrixX3d& vertices, std::vector<TetRecord>& tets) {
  const TetRecord* first_positive = nullptr;
  const TetRecord* first_negative = nullptr;
  size_t negatives = 0;
  for (const TetRecord& t : tets) {
    const double volume = signedVolume(vertices, t.vertices);
    if (isFlat(vertices, t.vertices, volume)) {
      throw FileFormatError(file, t.line, tetName(t) + ": zero volume (degenerate element)");
    }
    if (volume > 0.0) {
      if (!first_positive) first_positive = &t;
    } else {
      if (!first_negative) first_negative = &t;
      ++negatives;
    }
  }
  if (first_positive && first_negative) {
    // Blame the minority: it is the likelier mistake, and its first member is what to fix.
    const bool blame_negative = 2 * negatives <= tets.size();
    const TetRecord& bad = blame_negative ? *first_negative : *first_positive;
    const TetRecord& other = blame_negative ? *first_positive : *first_negative;
    throw FileFormatError(file, bad.line,
                          tetName(bad) + ": mixed orientation, its signed volume is " +
                              (blame_negative ? "negative" : "positive") + " but " + tetName(other) +
                              " (line " + std::to_string(other.line) + ") has the opposite sign");
  }
  if (first_negative) {
    for (TetRecord& t : tets) std::swap(t.vertices[1], t.vertices[2]);
  }
}

Scene solidSceneFromMesh(const std::string& name, const std::string& element_file,
                         const Eigen::MatrixX3d& vertices, std::vector<TetRecord> tets,
                         const SolidMaterial& material) {
  orientTets(element_file, vertices, tets);
  std::vector<Tet> elements;
  elements.reserve(tets.size());
  for (const TetRecord& t : tets) elements.push_back(Tet{t.vertices, material.stiffness});
  Scene s = sceneFromMesh(name, vertices, lumpMassesFromTets(vertices, elements, material.density));
  s.tets = std::move(elements);
  return s;
}

}  // namespace stabint::io
