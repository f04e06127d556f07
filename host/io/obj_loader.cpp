// Wavefront OBJ reader for cloth: only `v` and `f` matter; texture coordinates, normals, groups
// and materials are skipped.
#include "common/out_of_memory.hpp"
#include "io/mesh_scene.hpp"
#include "common/text_reader.hpp"
#include "scene/lumping.hpp"
#include "common/validation.hpp"

#include <stabint/io.hpp>

#include <algorithm>
#include <array>
#include <cstddef>
#include <utility>
#include <vector>

namespace stabint {

namespace {

struct Face {
  std::vector<long> vertices;  // 1-based as written, negatives already resolved
  int number;                  // 1-based count of faces, as a user would count them
  int line;
};

// Negative references count back from the vertices defined so far, so they are resolved now;
// positive ones may point forward and are checked once all vertices are known.
Face readFace(const io::TextReader& in, const std::vector<std::string>& tokens, int number, long vertices_so_far) {
  const std::string name = "face " + std::to_string(number);
  if (tokens.size() < 4) in.fail(name + ": needs at least 3 vertices, got " + std::to_string(tokens.size() - 1));
  Face face{{}, number, in.line()};
  for (size_t k = 1; k < tokens.size(); ++k) {
    const std::string ref = tokens[k].substr(0, tokens[k].find('/'));  // "v", "v/vt", "v//vn", "v/vt/vn"
    long index = in.parseInt(ref, name + " vertex index");
    if (index == 0) in.fail(name + ": vertex index 0 is invalid (OBJ indices start at 1)");
    if (index < 0) {
      const long written = index;
      index += vertices_so_far + 1;
      if (index < 1) {
        in.fail(name + ": relative vertex index " + std::to_string(written) + " points before the first vertex (" +
                std::to_string(vertices_so_far) + " defined so far)");
      }
    }
    face.vertices.push_back(index);
  }
  return face;
}

// No vertex twice in one face, in O(k log k) for a k-gon: comparing every pair took 15 s for a
// 200,000-gon. The corners are sorted by (vertex, position), so each vertex's first two
// occurrences are adjacent; the repeat reported is the one earliest in the face, as a reader
// scanning the line would find it.
void checkDistinctCorners(const std::string& file, const Face& face, const std::string& name) {
  std::vector<std::pair<long, std::size_t>> corners(face.vertices.size());
  for (std::size_t k = 0; k < corners.size(); ++k) corners[k] = {face.vertices[k], k};
  std::sort(corners.begin(), corners.end());
  std::size_t first = 0, second = corners.size();
  for (std::size_t k = 1; k < corners.size(); ++k) {
    if (corners[k].first == corners[k - 1].first && corners[k].second < second &&
        (k < 2 || corners[k - 2].first != corners[k].first)) {
      first = corners[k - 1].second;
      second = corners[k].second;
    }
  }
  if (second < corners.size()) {
    throw FileFormatError(file, face.line,
                          name + ": vertex " + std::to_string(face.vertices[second]) + " appears twice (corners " +
                              std::to_string(first + 1) + " and " + std::to_string(second + 1) + ")");
  }
}

// The fan triangles of every face, and for each the face it came from. A fan triangle that is
// flat (zero area for its size: collinear or coincident corners) or whose area overflows is an
// error naming the face and its corners: it would get no mass (or an infinite one), and as
// triangle strain it is refused anyway.
struct Fan {
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::size_t> face;  // index into the faces, per triangle
};

Fan fanTriangles(const std::string& file, const std::vector<Face>& faces, const Eigen::MatrixX3d& x) {
  const long num_vertices = static_cast<long>(x.rows());
  Fan fan;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const Face& face = faces[f];
    const std::string name = "face " + std::to_string(face.number);
    for (const long v : face.vertices) {
      if (v > num_vertices) {
        throw FileFormatError(
            file, face.line,
            name + ": vertex index " + std::to_string(v) + " out of range [1, " + std::to_string(num_vertices) + "]");
      }
    }
    checkDistinctCorners(file, face, name);
    // A fan from the first corner is exact for the convex polygons meshes are made of.
    for (size_t k = 1; k + 1 < face.vertices.size(); ++k) {
      const std::array<int, 3> t{static_cast<int>(face.vertices[0] - 1), static_cast<int>(face.vertices[k] - 1),
                                 static_cast<int>(face.vertices[k + 1] - 1)};
      const validation::RestShape shape = validation::restTriangle(x, t);
      if (!shape.fine()) {
        const std::string corners =
            face.vertices.size() == 3
                ? std::string()
                : " (the fan triangle of corners 1, " + std::to_string(k + 1) + ", " + std::to_string(k + 2) + ")";
        throw FileFormatError(file, face.line, name + corners + ": " + validation::restShapeProblem(shape));
      }
      fan.triangles.push_back(t);
      fan.face.push_back(f);
    }
  }
  return fan;
}

}  // namespace

static Scene loadObjClothUnguarded(const std::string& path, const ClothMaterial& material) {
  validation::checkDensity(material.areal_density, "ClothMaterial areal_density");
  io::TextReader in(path);
  io::VertexLines lines{path, "vertex", 1, {}};
  std::vector<Eigen::Vector3d> positions;
  std::vector<Face> faces;
  for (std::vector<std::string> tokens; in.nextLine(tokens);) {
    if (tokens[0] == "v") {
      const std::string name = "vertex " + std::to_string(positions.size() + 1);
      // x y z, then an optional weight w (the OBJ standard) or a colour r g b (a common
      // extension) or both, each a number; another count is not a vertex line this reader knows.
      const std::size_t values = tokens.size() - 1;
      if (values != 3 && values != 4 && values != 6 && values != 7)
        in.fail(name + ": expected 'v <x> <y> <z>' with an optional <w> and an optional colour <r> <g> <b>, got " +
                std::to_string(values) + " values");
      lines.lines.push_back(in.line());
      Eigen::Vector3d x;
      for (int c = 0; c < 3; ++c) x[c] = in.parseCoordinate(tokens[1 + c], name + " coordinate " + "xyz"[c]);
      for (std::size_t k = 4; k < tokens.size(); ++k) in.parseReal(tokens[k], name + " value " + std::to_string(k));
      positions.push_back(x);
    } else if (tokens[0] == "f") {
      faces.push_back(readFace(in, tokens, static_cast<int>(faces.size()) + 1, static_cast<long>(positions.size())));
    }
  }
  if (positions.empty()) in.fail("no vertices ('v' lines)");
  if (faces.empty()) in.fail("no faces ('f' lines)");

  Eigen::MatrixX3d x(positions.size(), 3);
  for (size_t i = 0; i < positions.size(); ++i) x.row(i) = positions[i].transpose();
  Fan fan = fanTriangles(path, faces, x);
  Eigen::VectorXd masses = Eigen::VectorXd::Zero(x.rows());
  if (const auto failure = lumping::addTriangles(x, fan.triangles, material.areal_density, "areal_density", masses)) {
    const Face& face = faces[fan.face[failure->element]];
    throw FileFormatError(path, face.line, "face " + std::to_string(face.number) + ": " + failure->what);
  }
  io::requireEveryVertexUsed(masses, lines, "face");
  Scene s = io::sceneFromMesh(io::sceneNameFromPath(path), x, std::move(masses));
  s.triangles = std::move(fan.triangles);
  if (material.model == ClothModel::Triangles) {
    addTriangleClothElements(s, material.strain_stiffness, material.strain_min, material.strain_max,
                             material.hinge_stiffness);
  } else {
    s.springs = clothSpringsFromTriangles(x, s.triangles, material.stretch_stiffness, material.bend_stiffness);
  }
  return s;
}

Scene loadObjCloth(const std::string& path, const ClothMaterial& material) {
  return reportingOutOfMemory("loadObjCloth", [&] { return loadObjClothUnguarded(path, material); });
}

}  // namespace stabint
