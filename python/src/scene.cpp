// The scene's classes: the elements and the other parts of a Scene, generated from their field
// tables (stabint/scene.hpp, through fields.hpp), Scene itself, the builders and the loaders.
#include "fields.hpp"

#include <type_traits>

namespace stabint::py {

using namespace nb::literals;

// What the scene's structs have beyond their fields (see bindExtras).
template <>
void bindExtras(nb::class_<PinTarget>& c) {
  c.def("at", &PinTarget::at, "t"_a).def("moving", &PinTarget::moving);
}
template <>
void bindExtras(nb::class_<Pin>& c) {
  c.def(
      "__init__",
      [](Pin* p, int vertex, double k, const Eigen::Vector3d& position) {
        new (p) Pin{vertex, k, PinTarget{}};
        p->target.position = position;
      },
      "vertex"_a, "stiffness"_a, "position"_a, "A static pin at `position`.");
}
template <>
void bindExtras(nb::class_<ForceField>& c) {
  c.def("at", &ForceField::at, "t"_a);
}
template <>
void bindExtras(nb::class_<Collider>& c) {
  c.def("moving", &Collider::moving);
}
// A collider's repr names its shape and the fields that describe that shape, then only the fields
// that differ from their defaults (a plane need not show a radius it ignores), e.g.
// "Collider(shape=ColliderShape.Sphere, center=[0.0, 0.5, 0.0], radius=0.2, friction=0.3)".
template <>
std::string structRepr<Collider>(nb::handle self) {
  const Collider& collider = nb::cast<const Collider&>(self);
  static const Collider defaults{};
  const auto describes = [&](const std::string& field) {
    switch (collider.shape) {
      case ColliderShape::Plane: return field == "center" || field == "normal";
      case ColliderShape::Sphere: return field == "center" || field == "radius";
      case ColliderShape::Box: return field == "center" || field == "half_extents";
      case ColliderShape::Capsule: return field == "center" || field == "end" || field == "radius";
      case ColliderShape::Mesh: return field == "center" || field == "mesh_vertices" || field == "mesh_triangles";
    }
    return true;
  };
  // Eigen compares matrices of one size only: a mesh's vertices differ from the empty default
  // by their row count first.
  const auto differs = [](const auto& value, const auto& other) {
    if constexpr (std::is_same_v<std::decay_t<decltype(value)>, Eigen::MatrixX3d>)
      return value.rows() != other.rows() || value != other;
    else
      return value != other;
  };
  std::string text = "Collider(shape=" + valueRepr(self.attr("shape"));
  std::apply(
      [&](const auto&... field) {
        const auto add = [&](const auto& f) {
          const std::string name = f.name;
          if (name != "shape" && (describes(name) || differs(collider.*(f.member), defaults.*(f.member))))
            text += ", " + name + "=" + valueRepr(self.attr(f.name));
        };
        (add(field), ...);
      },
      FieldTable<Collider>::fields);
  return text + ")";
}

void bindScene(nb::module_& m) {
  nb::class_<Scene> scene(m, "Scene",
                          "A simulation scene. Array properties return copies (assign to change them); "
                          "element lists (springs, tets, pins, ...) are views: append to edit the scene.");
  scene.def(nb::init<>()).def(nb::init<const Scene&>(), "other"_a, "A deep copy.");
  // Its fields from its table, and with them the classes of the elements and of the other parts
  // and their lists (SpringList, ...): a new element type's list in the table is all it takes.
  bindProperties(m, scene);
  // A summary rather than every array (a cloth's repr would print thousands of numbers): the name,
  // the counts the CLI prints, and what else the scene holds, e.g.
  // "<Scene 'cloth': 900 particles, 5102 springs, 2 pins; 1 body, 1682 surface triangles>".
  scene.def("__repr__", [](const Scene& s) {
    const auto count = [](std::size_t n, const char* one, const char* many) {
      return std::to_string(n) + " " + (n == 1 ? one : many);
    };
    std::string text = "<Scene " + nb::cast<std::string>(nb::repr(nb::str(s.name.c_str()))) + ": " +
                       count(static_cast<std::size_t>(s.numParticles()), "particle", "particles") + ", " +
                       elementSummary(s);
    std::string parts;
    const auto part = [&](std::size_t n, const char* one, const char* many) {
      if (n != 0) parts += (parts.empty() ? "; " : ", ") + count(n, one, many);
    };
    part(s.colliders.size(), "collider", "colliders");
    part(s.force_fields.size(), "force field", "force fields");
    part(s.bodies.size(), "body", "bodies");
    part(s.triangles.size(), "surface triangle", "surface triangles");
    return text + parts + ">";
  });
  scene.def_prop_ro("num_particles", &Scene::numParticles)
      .def(
          "validate", [](const Scene& s) { validateScene(s); },
          "Raises InvalidInputError naming the first offending element or field.");

  m.def("builtin_scene", &builtinScene, "name"_a, "params_json"_a = "{}", "label"_a = "builtin scene",
        "A built-in scene ('oscillator', 'chain', 'cloth', 'tetbar') with its builder's parameters as a "
        "JSON object text; prefer the shortcuts cloth_grid(**params) etc. Raises FileFormatError for an "
        "unknown name or parameter.");
  m.def("builtin_scene_names", &builtinSceneNames);
  m.def(
      "tet_surface", [](const Scene& s) { return trianglesCopy(tetSurface(s.tets)); }, "scene"_a,
      "The (m, 3) surface triangles of the scene's tets (positively oriented): the faces only one tet has, "
      "wound so that their normals point out of the body.");
  m.def("builtin_scene_parameters", &builtinSceneParameters, "name"_a);
  m.def(
      "cloth_grid_triangles", [](int nx, int ny) { return trianglesCopy(clothGridTriangles(nx, ny)); }, "nx"_a, "ny"_a,
      "The (m, 3) triangles of cloth_grid's nx by ny grid.");

  // The materials from their tables (stabint/events_io_fields.hpp), before the loaders' defaults.
  bindStruct<ClothMaterial>(m);
  bindStruct<SolidMaterial>(m);
  m.def("load_obj_cloth", &loadObjCloth, "path"_a, "material"_a = ClothMaterial(),
        "A Wavefront OBJ triangle mesh as cloth. Raises FileFormatError (file, line).");
  m.def("load_tetgen", &loadTetGen, "base_path"_a, "material"_a = SolidMaterial(),
        "A TetGen mesh from <base_path>.node and <base_path>.ele.");
  m.def("load_medit", &loadMedit, "path"_a, "material"_a = SolidMaterial(), "A Medit .mesh file.");
  m.def("load_scene_file", &loadSceneFile, "path"_a, "A JSON scene file (docs/scene-format.md), validated.");
  m.def("save_scene_file", &saveSceneFile, "scene"_a, "path"_a,
        "Writes the scene as an explicit JSON scene file that load_scene_file reads back exactly.");
}

}  // namespace stabint::py
