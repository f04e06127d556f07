#pragma once
/// @file
/// Mesh loaders. Every error in a file is a FileFormatError that names the file and the line; a
/// material whose density is not > 0 and finite is an InvalidInputError. What a loader derives is
/// checked where it is derived: a coordinate beyond 1e150 in magnitude, an element that is flat
/// (the relative test of validateScene) or whose volume, area or mass share overflows, and a vertex
/// in no element (it would have no mass) are errors at their line.
#include <stabint/scene.hpp>

#include <string>
#include <vector>

namespace stabint {

/// Material parameters applied to a loaded mesh.
struct ClothMaterial {
  double areal_density = 0.1;              ///< kg/m^2
  double stretch_stiffness = 1e3;          ///< springs along edges (model Springs)
  double bend_stiffness = 1e1;             ///< springs across interior edges (model Springs)
  ClothModel model = ClothModel::Springs;  ///< springs, or triangle strain and bending hinges
  double strain_stiffness = 1e3;           ///< triangle strain k, N/m (model Triangles)
  double strain_min = 1.0;                 ///< triangle strain limits (model Triangles)
  double strain_max = 1.0;                 ///< triangle strain limits (model Triangles)
  double hinge_stiffness = 1e-3;           ///< bending hinge k, J (model Triangles)
};
/// Material parameters applied to a loaded tet mesh.
struct SolidMaterial {
  double density = 1000.0;  ///< kg/m^3
  double stiffness = 1e5;   ///< tet strain stiffness (Pa)
};

/// Loads a Wavefront OBJ triangle mesh as cloth: vertices (`v x y z`, with an optional weight
/// `w` and an optional colour `r g b` after them, both ignored), faces (`f`, polygons are
/// fanned into triangles, `v/vt/vn` forms accepted, negative indices allowed) into
/// Scene::triangles; the elements of `material.model` (springs along edges and bending springs
/// across interior edges, or triangle strain and bending hinges); masses from the area. No pins,
/// no damping. Every vertex must be in a face, and no fan triangle may have zero area.
Scene loadObjCloth(const std::string& path, const ClothMaterial& material = {});

/// Loads a TetGen mesh from `<base>.node` and `<base>.ele` (0- or 1-based, attributes and
/// boundary markers ignored; every line has the fields its file's header announces, no more and
/// no fewer; a quadratic tet's mid-edge nodes are checked and ignored). Tets with negative signed
/// volume are reoriented only when every tet of the mesh has that orientation (a mesh-wide
/// convention); mixed or zero volumes are an error naming the element. Every point must be in a
/// tet (TetGen's -j drops those that are not).
Scene loadTetGen(const std::string& base_path, const SolidMaterial& material = {});

/// Loads a Medit `.mesh` file (sections Vertices and Tetrahedra; other sections are skipped),
/// with the same orientation rule as loadTetGen.
Scene loadMedit(const std::string& path, const SolidMaterial& material = {});

/// Loads a scene file (JSON, format described in docs/scene-format.md): explicit particles and
/// elements, built-in scenes by name, meshes (paths relative to the JSON file's directory), pins
/// selected by region. Every error is a FileFormatError naming the file and the JSON field path,
/// e.g. `scenes/foo.json: springs[3].stiffness: expected a number, got string`; malformed JSON
/// carries the line. The scene is validated before it is returned.
Scene loadSceneFile(const std::string& path);

/// A built-in scene ("oscillator", "chain", "cloth", "tetbar"; builders.hpp) with parameters
/// given as the text of a JSON object whose keys are the fields of the builder's parameter
/// struct, e.g. `{"nx": 50, "pinned": [0, 49], "model": "triangles"}`. Errors are
/// FileFormatError(label, 0, "params.<key>: ...").
Scene builtinScene(const std::string& name, const std::string& params_json = "{}",
                   const std::string& label = "builtin scene");

/// Names accepted by builtinScene, and the parameter names of one of them (for usage texts).
///@{
std::vector<std::string> builtinSceneNames();
std::vector<std::string> builtinSceneParameters(const std::string& name);
///@}

/// Writes `scene` as a JSON scene file in the explicit form (no builtin or mesh entries), with
/// every number written so that loadSceneFile reads back exactly the same scene. Throws
/// FileFormatError when the file cannot be written and InvalidInputError for a scene that does
/// not validate (JSON cannot hold non-finite numbers) or whose scene or body names are not UTF-8.
void saveSceneFile(const Scene& scene, const std::string& path);

}  // namespace stabint
