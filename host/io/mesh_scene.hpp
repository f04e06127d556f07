#pragma once
// What the mesh loaders share after parsing: turning file vertices and elements into a Scene,
// reading tet vertex indices, and the mesh-wide orientation rule of io.hpp.
#include "io/text_reader.hpp"

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
/// swapped); zero volume or a mix of signs -> FileFormatError in `file` at the tet's line.
void orientTets(const std::string& file, const Eigen::MatrixX3d& vertices, std::vector<TetRecord>& tets);

/// The solid scene of a tet mesh: oriented tets of the material's stiffness, masses lumped from
/// its density.
Scene solidSceneFromMesh(const std::string& name, const std::string& element_file,
                         const Eigen::MatrixX3d& vertices, std::vector<TetRecord> tets,
                         const SolidMaterial& material);

}  // namespace stabint::io
