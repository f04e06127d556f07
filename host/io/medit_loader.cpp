// Medit .mesh reader (ASCII; the format of Gmsh's and TetGen's -g output). The format is free:
// a keyword and its count may share a line or not, so it is read as a token stream.
#include "common/out_of_memory.hpp"
#include "io/mesh_scene.hpp"
#include "common/text_reader.hpp"
#include "common/validation.hpp"

#include <stabint/io.hpp>

#include <algorithm>
#include <cctype>
#include <optional>

namespace stabint {

namespace {

bool sameKeyword(const std::string& a, const char* b) {
  const std::string bs(b);
  return a.size() == bs.size() && std::equal(a.begin(), a.end(), bs.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

// Keywords start with a letter; everything in a section's body is a number.
bool isKeyword(const std::string& token) { return std::isalpha(static_cast<unsigned char>(token[0])) != 0; }

// The integer reference that ends a record starting on `line`. A keyword in its place means the
// record lacks it: the error names the record's line, where the mistake is, and the keyword.
void readReference(io::TextReader& in, const std::string& record, int line) {
  const std::string token = in.requireToken(record + " reference");
  if (isKeyword(token))
    in.failAt(line, record + ": no reference after its numbers (found the keyword '" + io::shown(token) + "' on line " +
                        std::to_string(in.line()) + ")");
  in.parseInt(token, record + " reference");
}

Eigen::MatrixX3d readVertices(io::TextReader& in, io::VertexLines& lines) {
  const int count = in.parseCount(in.requireToken("the number of vertices"), "number of vertices");
  std::vector<double> xyz;                   // row after row; the header's count is not trusted with an allocation
  xyz.reserve(3 * in.reserveFor(count, 8));  // "x y z ref": a number and a separator each
  for (int i = 0; i < count; ++i) {
    const std::string vertex = "vertex " + std::to_string(i + 1);
    for (int c = 0; c < 3; ++c) {
      const std::string token = in.requireToken(vertex + " of " + std::to_string(count));
      if (c == 0) lines.lines.push_back(in.line());
      xyz.push_back(in.parseCoordinate(token, vertex + " coordinate " + "xyz"[c]));
    }
    readReference(in, vertex, lines.lines.back());
  }
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(xyz.data(), count, 3);
}

std::vector<io::TetRecord> readTetrahedra(io::TextReader& in, int num_vertices) {
  const int count = in.parseCount(in.requireToken("the number of tetrahedra"), "number of tetrahedra");
  std::vector<io::TetRecord> tets;
  tets.reserve(in.reserveFor(count, 10));  // "a b c d ref"
  for (int i = 0; i < count; ++i) {
    io::TetRecord tet{{}, i + 1, 0};
    const std::string name = "tet " + std::to_string(tet.id);
    for (int k = 0; k < 4; ++k) {
      const std::string token = in.requireToken(name + " of " + std::to_string(count));
      if (k == 0) tet.line = in.line();
      tet.vertices[k] = io::parseVertexIndex(in, token, 1, num_vertices, name);
    }
    readReference(in, name, tet.line);
    tets.push_back(tet);
  }
  return tets;
}

}  // namespace

static Scene loadMeditUnguarded(const std::string& path, const SolidMaterial& material) {
  validation::checkDensity(material.density, "SolidMaterial density");
  io::TextReader in(path);
  io::VertexLines lines{path, "vertex", 1, {}};
  std::optional<Eigen::MatrixX3d> vertices;
  std::optional<std::vector<io::TetRecord>> tets;
  std::string token;
  bool more = in.nextToken(token);
  while (more) {
    if (!isKeyword(token)) in.fail("expected a section keyword, got '" + io::shown(token) + "'");
    if (sameKeyword(token, "End")) break;
    if (sameKeyword(token, "Dimension")) {
      const int dimension = in.parseInt(in.requireToken("the dimension"), "dimension");
      if (dimension != 3) in.fail("dimension " + std::to_string(dimension) + " is not supported, expected 3");
    } else if (sameKeyword(token, "Vertices")) {
      if (vertices) in.fail("second Vertices section");
      vertices = readVertices(in, lines);
    } else if (sameKeyword(token, "Tetrahedra")) {
      if (!vertices) in.fail("Tetrahedra section before the Vertices section");
      if (tets) in.fail("second Tetrahedra section");
      tets = readTetrahedra(in, static_cast<int>(vertices->rows()));
    } else {
      // MeshVersionFormatted, Triangles, Edges, Corners, ...: skip the section's numbers; the
      // token that ends the skip is already the next keyword.
      while ((more = in.nextToken(token)) && !isKeyword(token)) {
      }
      continue;
    }
    more = in.nextToken(token);
  }
  if (!vertices) in.fail("no Vertices section");
  if (!tets) in.fail("no Tetrahedra section");
  return io::solidSceneFromMesh(io::sceneNameFromPath(path), path, lines, *vertices, std::move(*tets), material);
}

Scene loadMedit(const std::string& path, const SolidMaterial& material) {
  return reportingOutOfMemory("loadMedit", [&] { return loadMeditUnguarded(path, material); });
}

}  // namespace stabint
