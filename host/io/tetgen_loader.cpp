// TetGen .node/.ele reader (https://wias-berlin.de/software/tetgen/fformats.html).
#include "common/out_of_memory.hpp"
#include "io/mesh_scene.hpp"
#include "common/text_reader.hpp"
#include "common/validation.hpp"

#include <stabint/io.hpp>

namespace stabint {

namespace {

// The header's optional count `index` (attributes, markers), 0 when absent; markers are 0 or 1.
int optionalCount(const io::TextReader& in, const std::vector<std::string>& header, std::size_t index, const char* what,
                  int most) {
  if (header.size() <= index) return 0;
  const int count = in.parseCount(header[index], what);
  if (count > most)
    in.fail(std::string(what) + " " + std::to_string(count) + " must be at most " + std::to_string(most));
  return count;
}

// "<what>: expected <fields>, got <n> fields" unless a record line has exactly `want` fields (the
// header's attributes and markers included): a line with more or fewer does not follow its
// header, and its values would be read from the wrong columns.
void expectFields(const io::TextReader& in, const std::vector<std::string>& tokens, int want, const std::string& what,
                  const std::string& fields) {
  if (static_cast<int>(tokens.size()) != want)
    in.fail(what + ": expected " + std::to_string(want) + " fields (" + fields + "), got " +
            std::to_string(tokens.size()));
}

struct Nodes {
  Eigen::MatrixX3d positions;
  int base = 0;  // TetGen numbers from 0 or 1, and .ele follows .node's choice
  io::VertexLines lines;
};

Nodes readNodes(const std::string& path) {
  io::TextReader in(path);
  const auto header = in.requireLine("the .node header '<#points> <dimension> <#attributes> <#markers>'");
  if (header.size() < 2 || header.size() > 4)
    in.fail("the .node header is '<#points> <dimension> [<#attributes> [<#markers>]]', got " +
            std::to_string(header.size()) + " fields");
  const int count = in.parseCount(header[0], "number of points");
  const int dimension = in.parseInt(header[1], "dimension");
  if (dimension != 3) in.fail("dimension " + std::to_string(dimension) + " is not supported, expected 3");
  const int attributes = optionalCount(in, header, 2, "number of point attributes", 1 << 20);
  const int markers = optionalCount(in, header, 3, "number of boundary markers", 1);
  const std::string fields = "<index> <x> <y> <z>, " + std::to_string(attributes) + " attributes, " +
                             std::to_string(markers) + " boundary markers";

  Nodes nodes;
  nodes.lines.file = path;
  nodes.lines.noun = "point";
  std::vector<double> xyz;                   // row after row; the header's count is not trusted with an allocation
  xyz.reserve(3 * in.reserveFor(count, 8));  // "i x y z": a number and a separator each
  for (int i = 0; i < count; ++i) {
    const std::string point = "point " + std::to_string(i);
    const auto tokens = in.requireLine(point + " of " + std::to_string(count));
    expectFields(in, tokens, 4 + attributes + markers, point, fields);
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
    // Attributes and the marker are not used, but they are numbers in a well-formed file.
    for (int a = 0; a < attributes; ++a)
      in.parseReal(tokens[std::size_t(4 + a)], "point " + std::to_string(id) + " attribute " + std::to_string(a));
    if (markers > 0) in.parseInt(tokens[std::size_t(4 + attributes)], "point " + std::to_string(id) + " marker");
  }
  nodes.positions = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(xyz.data(), count, 3);
  return nodes;
}

std::vector<io::TetRecord> readElements(const std::string& path, const Nodes& nodes) {
  io::TextReader in(path);
  const auto header = in.requireLine("the .ele header '<#tetrahedra> <nodes per tet> <#attributes>'");
  if (header.size() < 2 || header.size() > 3)
    in.fail("the .ele header is '<#tetrahedra> <nodes per tet> [<#attributes>]', got " + std::to_string(header.size()) +
            " fields");
  const int count = in.parseCount(header[0], "number of tetrahedra");
  const int per_tet = in.parseInt(header[1], "nodes per tetrahedron");
  // Quadratic (10-node) tets list their four corners first; the mid-edge nodes are ignored.
  if (per_tet != 4 && per_tet != 10) in.fail("nodes per tetrahedron " + std::to_string(per_tet) + " must be 4 or 10");
  const int attributes = optionalCount(in, header, 2, "number of tetrahedron attributes", 1 << 20);
  const std::string fields =
      "<index>, " + std::to_string(per_tet) + " node numbers, " + std::to_string(attributes) + " attributes";

  std::vector<io::TetRecord> tets;
  tets.reserve(in.reserveFor(count, 2 * (1 + per_tet)));  // "i a b c d": a number and a separator each
  for (int i = 0; i < count; ++i) {
    const auto tokens = in.requireLine("tetrahedron " + std::to_string(i) + " of " + std::to_string(count));
    expectFields(in, tokens, 1 + per_tet + attributes, "tetrahedron " + std::to_string(i), fields);
    io::TetRecord tet{{}, in.parseInt(tokens[0], "tetrahedron number"), in.line()};
    const std::string name = "tet " + std::to_string(tet.id);
    // The mid-edge nodes of a quadratic tet are checked as node numbers too, not used.
    for (int k = 0; k < per_tet; ++k) {
      const int vertex = io::parseVertexIndex(in, tokens[std::size_t(1 + k)], nodes.base,
                                              static_cast<int>(nodes.positions.rows()), name);
      if (k < 4) tet.vertices[std::size_t(k)] = vertex;
    }
    for (int a = 0; a < attributes; ++a)
      in.parseReal(tokens[std::size_t(1 + per_tet + a)], name + " attribute " + std::to_string(a));
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
