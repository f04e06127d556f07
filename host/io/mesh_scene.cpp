#include "io/mesh_scene.hpp"
#include "scene/lumping.hpp"
#include "common/validation.hpp"

#include <cmath>
#include <filesystem>
#include <numeric>

namespace stabint::io {

// A file name is bytes (Latin-1 names exist); the scene name must be text that a scene file can hold.
std::string sceneNameFromPath(const std::string& path) {
  return validUtf8(std::filesystem::path(path).stem().string());
}

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

std::string tetName(const TetRecord& t) { return "tet " + std::to_string(t.id); }

}  // namespace

void orientTets(const std::string& file, const Eigen::MatrixX3d& vertices, std::vector<TetRecord>& tets) {
  const TetRecord* first_positive = nullptr;
  const TetRecord* first_negative = nullptr;
  size_t negatives = 0;
  for (const TetRecord& t : tets) {
    const validation::RestShape shape = validation::restTet(vertices, t.vertices);
    if (!shape.fine()) throw FileFormatError(file, t.line, tetName(t) + ": " + validation::restShapeProblem(shape));
    if (shape.measure > 0.0) {
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
                              (blame_negative ? "negative" : "positive") + " but " + tetName(other) + " (line " +
                              std::to_string(other.line) + ") has the opposite sign");
  }
  if (first_negative) {
    for (TetRecord& t : tets) std::swap(t.vertices[1], t.vertices[2]);
  }
}

void requireEveryVertexUsed(const Eigen::VectorXd& masses, const VertexLines& where, const std::string& element) {
  for (Eigen::Index k = 0; k < masses.size(); ++k) {
    if (masses[k] == 0.0) {
      throw FileFormatError(where.file, where.lines[k],
                            where.noun + " " + std::to_string(k + where.first_number) + " is in no " + element +
                                ", so it would have no mass; remove it from the file");
    }
  }
}

Scene solidSceneFromMesh(const std::string& name, const std::string& element_file, const VertexLines& vertex_lines,
                         const Eigen::MatrixX3d& vertices, std::vector<TetRecord> tets, const SolidMaterial& material) {
  orientTets(element_file, vertices, tets);
  std::vector<Tet> elements;
  elements.reserve(tets.size());
  for (const TetRecord& t : tets) elements.push_back(Tet{t.vertices, material.stiffness});
  Eigen::VectorXd masses = Eigen::VectorXd::Zero(vertices.rows());
  if (const auto failure = lumping::addTets(vertices, elements, material.density, "density", masses)) {
    const TetRecord& t = tets[failure->element];
    throw FileFormatError(element_file, t.line, tetName(t) + ": " + failure->what);
  }
  requireEveryVertexUsed(masses, vertex_lines, "tetrahedron");
  Scene s = sceneFromMesh(name, vertices, std::move(masses));
  s.tets = std::move(elements);
  return s;
}

}  // namespace stabint::io
