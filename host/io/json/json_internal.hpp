#pragma once
// What the files of the JSON scene format (docs/scene-format.md) share: the Field that names the
// JSON path in every error, and the pieces one concern's file takes from another's.
#include <stabint/events.hpp>
#include <stabint/scene.hpp>

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <filesystem>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace stabint {
class ElementType;
}

namespace stabint::io {

using json = nlohmann::json;
using ordered = nlohmann::ordered_json;

inline constexpr const char* kFormatName = "stabint-scene";
inline constexpr int kFormatVersion = 1;

// The value of an enum (count values named by nameOf: colliderShapeName, ...) whose name is
// exactly `name`, as scene files spell it; none when no value has it.
template <class Enum>
std::optional<Enum> valueNamed(const std::string& name, const char* (*nameOf)(Enum), int count) {
  for (int i = 0; i < count; ++i)
    if (name == nameOf(static_cast<Enum>(i))) return static_cast<Enum>(i);
  return std::nullopt;
}

// --- field.cpp ------------------------------------------------------------------------------------

// A JSON value together with where it sits ("springs[3].stiffness"), so that every check can
// name the field. Keys starting with '_' are comments and are ignored everywhere.
class Field {
 public:
  Field(const json& value, std::string path, const std::string& file)
      : value_(&value), path_(std::move(path)), file_(&file) {}

  const json& value() const { return *value_; }
  const std::string& path() const { return path_; }

  [[noreturn]] void fail(const std::string& message) const;

  void requireObject() const;
  void requireArray() const;

  std::optional<Field> find(const std::string& key) const;
  Field member(const std::string& key) const;
  bool has(const std::string& key) const { return find(key).has_value(); }

  size_t size() const;
  Field operator[](size_t i) const;

  /// Unknown keys are almost always typos ("stifness"): reject them rather than run a scene
  /// with a silently defaulted value.
  void allowOnly(const std::set<std::string>& keys) const;

  double number() const;
  // An event's value (keyframe, grab or element stiffness, impulse, collider velocity): the rule
  // of per-frame input, finite and at most 1e150, checked at load so that the file and the event
  // are named, not when the event is played.
  double eventValue() const;
  Eigen::Vector3d eventVector() const;
  double nonNegative() const;
  double positive() const;
  int integer() const;
  /// A particle index of a scene with `n` particles.
  int particle(int n) const;
  std::string string() const;
  Eigen::Vector3d vector3() const;
  std::vector<int> particles(int n) const;

  static std::string text(double x);

 private:
  std::string shortDump() const;
  static void brief(const json& v, std::string& out);

  const json* value_;
  std::string path_;
  const std::string* file_;
};

// The text of a JSON file parsed, refusing what the JSON library would pass over silently (NUL
// bytes, duplicate keys) or could not walk (deep nesting); errors name `file` and the line.
json parseJson(const std::string& text, const std::string& file);

// --- builtin_scenes.cpp ---------------------------------------------------------------------------

// A name as clothModelName prints it ("springs", "triangles").
ClothModel clothModel(const Field& f);
// Built-in scene `name` with the builder parameters in `params` (an object; `extra` keys belong
// to the caller); `name_field` is named when the name is unknown.
Scene builtinFromField(const std::string& name, const Field& params, const std::set<std::string>& extra,
                       const Field& name_field);

// --- mesh_reader.cpp ------------------------------------------------------------------------------

// A "mesh" entry of a scene file ({"file", "type", material keys, "translate", "damping",
// "name"}) as a scene; a relative file is relative to `dir`.
Scene meshFromField(const Field& mesh, const std::filesystem::path& dir);

// --- scene_reader.cpp -----------------------------------------------------------------------------

Scene sceneFromJson(const json& doc, const std::string& file);
// The particles in a region of the rest shape, a slab {"axis", "min", "max"} or a box
// {"min": [x, y, z], "max": [x, y, z]}; selecting none is an error.
std::vector<int> selectWhere(const Field& where, const Scene& s);
// JSON key of a type with a generic form: its identifier, plural ("triangle_strains").
std::string genericKey(const ElementType& type);
std::vector<const ElementType*> genericTypes();

// --- scene_writer.cpp -----------------------------------------------------------------------------

ordered vec(const Eigen::Vector3d& v);
ordered sceneToJson(const Scene& s);
// `v` written to `out` at `indent`, one item per line once a container no longer fits on one.
void pretty(std::string& out, const ordered& v, int indent);

// --- events_json.cpp ------------------------------------------------------------------------------

// The "events" list of a scene file, against its scene `s` (indices in range, "where" selected
// on its rest shape); the ordering rules are EventScript's, reported at the event's path.
EventScript readEvents(const Field& list, const Scene& s);
ordered eventToJson(const ScriptedEvent& ev);

}  // namespace stabint::io
