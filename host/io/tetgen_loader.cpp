// TetGen .node/.ele reader (https://wias-berlin.de/software/tetgen/fformats.html).
#include "out_of_memory.hpp"
#include "io/mesh_scene.hpp"
#include "io/text_reader.hpp"
#include "validation.hpp"

#include <stabint/io.hpp>

namespace stabint {

namespace {

struct Nodes {
  Eigen::MatrixX3d positions;
  int base = 0;  // TetGen numbers from 0 or 1, and .ele follows .node's choice
  io::VertexLines lines;
};

Nodes readNodes(const std::string& path) {
  io::TextReader in(path);
  const auto header = in.requireLine("the .node header '<#points> <dimension> <#attributes> <#markers>'");
  if (header.size() < 2) in.fail("the .node header needs at least '<#points> <dimension>'");
  const int count = in.parseCount(header[0], "number of points");
  const int dimension = in.parseInt(header[1], "dimension");
  if (dimension != 3) in.fail("dimension " + std::to_string(dimension) + " is not supported, expected 3");

  Nodes nodes;
  nodes.lines.file = path;
  nodes.lines.noun = "point";
  std::vector<double> xyz;                   // row after row; the header's count is not trusted with an allocation
  xyz.reserve(3 * in.reserveFor(count, 8));  // "i x y z": a number and a separator each
  for (int i = 0; i < count; ++i) {
    const std::string point = "point " + std::to_string(i);
    const auto tokens = in.requireLine(point + " of " + std::to_string(count));
    if (tokens.size() < 4)
      in.fail(point + ": expected '<index> <x> <y> <z>', got " + std::to_string(tokens.size()) + " fields");
    const int id = in.parseInt(tokens[0], point + " number");
    if (i == 0) {
      if (id != 0 && id != 1) in.fail("first point is numbered " + std::to_string(id) + ", expected 0 or 1");
      nodes.base = id;
      nodes.lines.first_number = id;
    } else if (id != nodes.base + i) {
      in.fail("point numbered " + std::to_string(id) + ", expected " + std::to_string(nodes.base + i) +
              " (points must be numbered consecutively)");
    }
    nodes.lines.lines.push_back(in.line());
    for (int c = 0; c < 3; ++c) {
      xyz.push_back(in.parseCoordinate(tokens[1 + c], "point " + std::to_string(id) + " coordinate " + "xyz"[c]));
    }
  }
  nodes.positions = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(xyz.data(), count, 3);
  return nodes;
}

std::vector<io::TetRecord> readElements(const std::string& path, const Nodes& nodes) {
  io::TextReader in(path);
  const auto header = in.requireLine("the .ele header '<#tetrahedra> <nodes per tet> <#attributes>'");
  if (header.size() < 2) in.fail("the .ele header needs at least '<#tetrahedra> <nodes per tet>'");
  const int count = in.parseCount(header[0], "number of tetrahedra");
  const int per_tet = in.parseInt(header[1], "nodes per tetrahedron");
  // Quadratic (10-node) tets list their four corners first; the mid-edge nodes are ignored.
  if (per_tet != 4 && per_tet != 10) in.fail("nodes per tetrahedron " + std::to_string(per_tet) + " must be 4 or 10");

  std::vector<io::TetRecord> tets;
  tets.reserve(in.reserveFor(count, 2 * (1 + per_tet)));  // "i a b c d": a number and a separator each
  for (int i = 0; i < count; ++i) {
    const auto tokens = in.requireLine("tetrahedron " + std::to_string(i) + " of " + std::to_string(count));
    if (static_cast<int>(tokens.size()) < 1 + per_tet) {
      in.fail("tetrahedron " + std::to_string(i) + ": expected '<index>' and " + std::to_string(per_tet) +
              " node numbers, got " + std::to_string(tokens.size()) + " fields");
    }
    io::TetRecord tet{{}, in.parseInt(tokens[0], "tetrahedron number"), in.line()};
    const std::string name = "tet " + std::to_string(tet.id);
    for (int k = 0; k < 4; ++k) {
      tet.vertices[k] =
          io::parseVertexIndex(in, tokens[1 + k], nodes.base, static_cast<int>(nodes.positions.rows()), name);
    }
    tets.push_back(tet);
  }
  return tets;
}

// Accept "mesh", "mesh.node" and "mesh.ele" alike: users often pass one of the two files.
std::string stripTetGenExtension(const std::string& path) {
  for (const char* ext : {".node", ".ele"}) {
    const std::string e(ext);
    if (path.size() > e.size() && path.compare(path.size() - e.size(), e.size(), e) == 0) {
      return path.substr(0, path.size() - e.size());
    }
  }
  return path;
}

}  // namespace

static Scene loadTetGenUnguarded(const std::string& base_path, const SolidMaterial& material) {
  validation::checkDensity(material.density, "SolidMaterial density");
  const std::string base = stripTetGenExtension(base_path);
  const Nodes nodes = readNodes(base + ".node");
  const std::string ele = base + ".ele";
  return io::solidSceneFromMesh(io::sceneNameFromPath(base), ele, nodes.lines, nodes.positions,
                                readElements(ele, nodes), material);
}

Scene loadTetGen(const std::string& base_path, const SolidMaterial& material) {
  return reportingOutOfMemory("loadTetGen", [&] { return loadTetGenUnguarded(base_path, material); });
}

}  // namespace stabint
