#pragma once
// What the mesh loaders share after parsing: turning file vertices and elements into a Scene,
// reading tet vertex indices, and the mesh-wide orientation rule of io.hpp.
#include "common/text_reader.hpp"

#include <stabint/io.hpp>

#include <array>
#include <string>
#include <vector>

namespace stabint::io {

/// A tet as read from a file, with what an error message needs to point back at it.
struct TetRecord {
  std::array<int, 4> vertices;  // 0-based
  long id;                      // the element's number as the file shows it
  int line;                     // 1-based line in `file`
};

/// Where the vertices of a mesh were read, for an error about one: vertex k (0-based) is
/// "<noun> <k + first_number>" at line lines[k] of `file`.
struct VertexLines {
  std::string file;
  std::string noun;  // "vertex", "point"
  int first_number = 1;
  std::vector<int> lines;
};

/// Scene name from a path: the file name without directory and extension, as UTF-8 (a byte that
/// is not becomes U+FFFD).
std::string sceneNameFromPath(const std::string& path);

/// Loaded scenes start at rest in their rest shape, under default gravity, as one undamped body.
/// `masses` must already be lumped.
Scene sceneFromMesh(const std::string& name, const Eigen::MatrixX3d& vertices, Eigen::VectorXd masses);

/// Converts `token` (a `base`-based vertex number) to a 0-based index in [0, num_vertices), or
/// fails naming `element` and the index as written.
int parseVertexIndex(const TextReader& reader, const std::string& token, int base, int num_vertices,
                     const std::string& element);

/// Applies the orientation rule: all tets negative -> each is reoriented (vertices 1 and 2
/// swapped); a flat tet, one whose volume overflows, or a mix of signs -> FileFormatError in
/// `file` at the tet's line.
void orientTets(const std::string& file, const Eigen::MatrixX3d& vertices, std::vector<TetRecord>& tets);

/// Every vertex of a mesh gets mass from an element: one in no `element` (e.g. "tetrahedron")
/// would have none, and a tiny made-up mass is not what the file meant (docs/scene-format.md,
/// "Meshes"). FileFormatError at the first such vertex's line.
void requireEveryVertexUsed(const Eigen::VectorXd& masses, const VertexLines& where, const std::string& element);

/// The solid scene of a tet mesh: oriented tets of the material's stiffness, masses lumped from
/// its density; a mass share that overflows is an error at its tet's line, a vertex in no tet
/// one at the vertex's line.
Scene solidSceneFromMesh(const std::string& name, const std::string& element_file, const VertexLines& vertex_lines,
                         const Eigen::MatrixX3d& vertices, std::vector<TetRecord> tets, const SolidMaterial& material);

}  // namespace stabint::io
