#pragma once
// What the JSON scene loader knows beyond the Scene itself: the surface triangles of the parts
// that have one (cloth grids, OBJ meshes, "triangles" lists). The Scene model has no triangles
// (springs carry cloth), but a viewer wants faces; stabint-run writes them into its OBJ frames.
#include <stabint/scene.hpp>

#include <array>
#include <string>
#include <vector>

namespace stabint::io {

struct SceneWithSurface {
  Scene scene;
  std::vector<std::array<int, 3>> triangles;  // particle indices of the scene; may be empty
};

/// loadSceneFile, keeping the surface triangles.
SceneWithSurface loadSceneFileWithSurface(const std::string& path);

/// A built-in scene ("oscillator", "chain", "cloth", "tetbar") with parameters given as the text
/// of a JSON object whose keys are the fields of the builder's parameter struct (builders.hpp),
/// e.g. `{"nx": 50, "pinned": [0, 49]}`. Errors are FileFormatError(label, 0, "<key>: ...").
SceneWithSurface builtinScene(const std::string& name, const std::string& params_json, const std::string& label);

/// Names accepted by builtinScene, and the parameter names of one of them (for usage texts).
std::vector<std::string> builtinSceneNames();
std::vector<std::string> builtinSceneParameters(const std::string& name);

}  // namespace stabint::io
