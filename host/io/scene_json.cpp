// JSON scene files (docs/scene-format.md): the explicit form saveSceneFile writes, plus the
// conveniences people write by hand: built-in scenes by name, meshes next to the JSON file, pins
// and particle sets selected by region. Every error names the file and the JSON field path.
#include "out_of_memory.hpp"
#include "elements/element_type.hpp"
#include "io/mesh_scene.hpp"
#include "io/text_reader.hpp"
#include "scene/scene_batch.hpp"
#include "scene/lumping.hpp"
#include "scene/validation.hpp"

#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/events.hpp>
#include <stabint/io.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <utility>
#include <variant>
#include <vector>

namespace stabint::io {

namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;

constexpr const char* kFormatName = "stabint-scene";
constexpr int kFormatVersion = 1;

// --- reading fields with their path -------------------------------------------------------------

// A JSON value together with where it sits ("springs[3].stiffness"), so that every check can
// name the field. Keys starting with '_' are comments and are ignored everywhere.
class Field {
 public:
  Field(const json& value, std::string path, const std::string& file)
      : value_(&value), path_(std::move(path)), file_(&file) {}

  const json& value() const { return *value_; }
  const std::string& path() const { return path_; }

  [[noreturn]] void fail(const std::string& message) const {
    throw FileFormatError(*file_, 0, (path_.empty() ? std::string("top level") : path_) + ": " + message);
  }

  void requireObject() const {
    if (!value_->is_object()) fail(std::string("expected an object, got ") + value_->type_name());
  }
  void requireArray() const {
    if (!value_->is_array()) fail(std::string("expected an array, got ") + value_->type_name());
  }

  std::optional<Field> find(const std::string& key) const {
    requireObject();
    const auto it = value_->find(key);
    if (it == value_->end()) return std::nullopt;
    return Field(*it, path_.empty() ? key : path_ + "." + key, *file_);
  }
  Field member(const std::string& key) const {
    auto f = find(key);
    if (!f) fail("missing field '" + key + "'");
    return *f;
  }
  bool has(const std::string& key) const { return find(key).has_value(); }

  size_t size() const {
    requireArray();
    return value_->size();
  }
  Field operator[](size_t i) const {
    requireArray();
    return Field((*value_)[i], path_ + "[" + std::to_string(i) + "]", *file_);
  }

  /// Unknown keys are almost always typos ("stifness"): reject them rather than run a scene
  /// with a silently defaulted value.
  void allowOnly(const std::set<std::string>& keys) const {
    requireObject();
    for (const auto& item : value_->items()) {
      if (item.key().empty() || item.key()[0] == '_') continue;
      if (!keys.count(item.key())) {
        std::string expected;
        for (const auto& k : keys) expected += (expected.empty() ? "" : ", ") + k;
        fail("unknown field '" + shown(item.key()) + "' (expected one of: " + expected + ")");
      }
    }
  }

  double number() const {
    if (!value_->is_number()) fail(std::string("expected a number, got ") + value_->type_name());
    const double x = value_->get<double>();
    if (!std::isfinite(x)) fail("expected a finite number");
    return x;
  }
  // An event's value (keyframe, grab or element stiffness, impulse, collider velocity): the rule
  // of per-frame input, finite and at most 1e150, checked at load so that the file and the event
  // are named, not when the event is played.
  double eventValue() const {
    const double x = number();
    if (!(std::abs(x) <= validation::kMaxMagnitude)) fail(text(x) + " exceeds 1e150 in magnitude");
    return x;
  }
  Eigen::Vector3d eventVector() const {
    if (!value_->is_array() || value_->size() != 3)
      fail("expected an array of 3 numbers [x, y, z], got " + shortDump());
    return Eigen::Vector3d((*this)[0].eventValue(), (*this)[1].eventValue(), (*this)[2].eventValue());
  }
  double nonNegative() const {
    const double x = number();
    if (x < 0.0) fail("must be >= 0, got " + text(x));
    return x;
  }
  double positive() const {
    const double x = number();
    if (!(x > 0.0)) fail("must be > 0, got " + text(x));
    return x;
  }
  int integer() const {
    if (value_->is_number_float()) {
      const double x = value_->get<double>();
      if (std::isfinite(x) && x == std::floor(x) && std::abs(x) <= INT_MAX) return static_cast<int>(x);
      fail("expected an integer, got " + value_->dump());
    }
    if (!value_->is_number()) fail(std::string("expected an integer, got ") + value_->type_name());
    if (value_->is_number_unsigned()) {
      if (value_->get<unsigned long long>() > static_cast<unsigned long long>(INT_MAX)) fail("integer out of range");
      return static_cast<int>(value_->get<unsigned long long>());
    }
    const long long v = value_->get<long long>();
    if (v < INT_MIN || v > INT_MAX) fail("integer out of range");
    return static_cast<int>(v);
  }
  /// A particle index of a scene with `n` particles.
  int particle(int n) const {
    const int i = integer();
    if (i < 0 || i >= n) fail("particle index " + std::to_string(i) + " out of range [0, " + std::to_string(n) + ")");
    return i;
  }
  std::string string() const {
    if (!value_->is_string()) fail(std::string("expected a string, got ") + value_->type_name());
    return value_->get<std::string>();
  }
  Eigen::Vector3d vector3() const {
    if (!value_->is_array() || value_->size() != 3)
      fail("expected an array of 3 numbers [x, y, z], got " + shortDump());
    return Eigen::Vector3d((*this)[0].number(), (*this)[1].number(), (*this)[2].number());
  }
  std::vector<int> particles(int n) const {
    std::vector<int> out(size());
    for (size_t i = 0; i < out.size(); ++i) out[i] = (*this)[i].particle(n);
    return out;
  }

  static std::string text(double x) {
    std::ostringstream s;
    s << x;
    return s.str();
  }

 private:
  // At most 40 characters of the value, escaped. Only as much of the value is walked as is
  // shown: dump() of the whole value recursed to its bottom (70,000 levels overflowed the stack)
  // and copied a million entries to show forty characters.
  std::string shortDump() const {
    std::string d;
    brief(*value_, d);
    return shown(d.size() > 40 ? d.substr(0, 37) + "..." : d);
  }
  static void brief(const json& v, std::string& out) {
    if (!v.is_structured()) {
      out += v.dump();
      return;
    }
    out += v.is_array() ? '[' : '{';
    for (auto it = v.begin(); it != v.end() && out.size() <= 40; ++it) {
      if (it != v.begin()) out += ',';
      if (v.is_object()) out += json(it.key()).dump() + ':';
      brief(*it, out);  // each level adds a character: at most about 40 deep
    }
    out += v.is_array() ? ']' : '}';
  }

  const json* value_;
  std::string path_;
  const std::string* file_;
};

// --- built-in scenes ------------------------------------------------------------------------------

// One list of parameter names per builder, used both to read them and to list them.
template <typename Visit>
void visitParams(Visit&& v, LinearOscillatorParams& p) {
  v("mass", p.mass);
  v("stiffness", p.stiffness);
  v("amplitude", p.amplitude);
}
template <typename Visit>
void visitParams(Visit&& v, ChainPendulumParams& p) {
  v("particles", p.particles);
  v("total_mass", p.total_mass);
  v("length", p.length);
  v("stiffness", p.stiffness);
  v("pin_stiffness", p.pin_stiffness);
  v("gravity", p.gravity);
}
template <typename Visit>
void visitParams(Visit&& v, ClothGridParams& p) {
  v("nx", p.nx);
  v("ny", p.ny);
  v("width", p.width);
  v("height", p.height);
  v("areal_density", p.areal_density);
  v("stretch_stiffness", p.stretch_stiffness);
  v("shear_stiffness", p.shear_stiffness);
  v("bend_stiffness", p.bend_stiffness);
  v("model", p.model);
  v("strain_stiffness", p.strain_stiffness);
  v("strain_min", p.strain_min);
  v("strain_max", p.strain_max);
  v("hinge_stiffness", p.hinge_stiffness);
  v("pin_stiffness", p.pin_stiffness);
  v("pinned", p.pinned);
  v("damping", p.damping);
}
template <typename Visit>
void visitParams(Visit&& v, TetBarParams& p) {
  v("nx", p.nx);
  v("ny", p.ny);
  v("nz", p.nz);
  v("length", p.length);
  v("width", p.width);
  v("density", p.density);
  v("stiffness", p.stiffness);
  v("pin_stiffness", p.pin_stiffness);
  v("damping", p.damping);
}

// "springs" or "triangles".
ClothModel clothModel(const Field& f) {
  const std::string name = f.string();
  if (name == "springs") return ClothModel::Springs;
  if (name == "triangles") return ClothModel::Triangles;
  f.fail("unknown cloth model '" + shown(name) + "' (expected springs or triangles)");
}

struct ParamReader {
  const Field& params;
  std::set<std::string>& known;
  void operator()(const char* key, int& out) const {
    known.insert(key);
    if (auto f = params.find(key)) out = f->integer();
  }
  void operator()(const char* key, double& out) const {
    known.insert(key);
    if (auto f = params.find(key)) out = f->number();
  }
  void operator()(const char* key, ClothModel& out) const {
    known.insert(key);
    if (auto f = params.find(key)) out = clothModel(*f);
  }
  void operator()(const char* key, std::vector<int>& out) const {
    known.insert(key);
    if (auto f = params.find(key)) {
      out.resize(f->size());
      for (size_t i = 0; i < out.size(); ++i) out[i] = (*f)[i].integer();  // range: the builder checks
    }
  }
};

struct ParamNames {
  std::vector<std::string>& names;
  template <typename T>
  void operator()(const char* key, T&) const {
    names.emplace_back(key);
  }
};

// Reads the builder parameters from `params` (an object; `extra` keys belong to the caller).
template <typename Params, typename Make>
Scene buildWith(const Field& params, const std::set<std::string>& extra, Params& p, Make make) {
  std::set<std::string> known = extra;
  visitParams(ParamReader{params, known}, p);
  params.allowOnly(known);
  try {
    return make(p);
  } catch (const InvalidInputError& e) {
    params.fail(e.what());
  }
}

Scene builtinFromField(const std::string& name, const Field& params, const std::set<std::string>& extra,
                       const Field& name_field) {
  Scene out;
  if (name == "oscillator") {
    LinearOscillatorParams p;
    out = buildWith(params, extra, p, [](const auto& q) { return makeLinearOscillator(q); });
  } else if (name == "chain") {
    ChainPendulumParams p;
    out = buildWith(params, extra, p, [](const auto& q) { return makeChainPendulum(q); });
  } else if (name == "cloth") {
    ClothGridParams p;
    out = buildWith(params, extra, p, [](const auto& q) { return makeClothGrid(q); });
  } else if (name == "tetbar") {
    TetBarParams p;
    out = buildWith(params, extra, p, [](const auto& q) { return makeTetBar(q); });
  } else {
    name_field.fail("unknown built-in scene '" + shown(name) + "' (expected oscillator, chain, cloth or tetbar)");
  }
  return out;
}

// --- meshes ---------------------------------------------------------------------------------------

std::string lowerExtension(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

Scene meshFromField(const Field& mesh, const fs::path& dir) {
  mesh.requireObject();
  const Field file_field = mesh.member("file");
  const fs::path relative = file_field.string();
  const fs::path path = relative.is_absolute() ? relative : dir / relative;

  std::string type;
  if (auto t = mesh.find("type")) {
    type = t->string();
    if (type != "obj" && type != "tetgen" && type != "medit") {
      t->fail("unknown mesh type '" + shown(type) + "' (expected obj, tetgen or medit)");
    }
  } else {
    const std::string ext = lowerExtension(path);
    if (ext == ".obj")
      type = "obj";
    else if (ext == ".mesh")
      type = "medit";
    else if (ext == ".node" || ext == ".ele")
      type = "tetgen";
    else
      file_field.fail("cannot tell the mesh type from '" + shown(relative.string()) +
                      "'; add \"type\": obj, tetgen or medit");
  }

  const std::set<std::string> common = {"file", "type", "translate", "damping", "name"};
  Scene out;
  try {
    if (type == "obj") {
      std::set<std::string> keys = common;
      keys.insert({"areal_density", "model", "stretch_stiffness", "bend_stiffness", "strain_stiffness", "strain_min",
                   "strain_max", "hinge_stiffness"});
      mesh.allowOnly(keys);
      ClothMaterial m;
      if (auto f = mesh.find("areal_density")) m.areal_density = f->positive();
      if (auto f = mesh.find("model")) m.model = clothModel(*f);
      if (auto f = mesh.find("stretch_stiffness")) m.stretch_stiffness = f->nonNegative();
      if (auto f = mesh.find("bend_stiffness")) m.bend_stiffness = f->nonNegative();
      if (auto f = mesh.find("strain_stiffness")) m.strain_stiffness = f->nonNegative();
      if (auto f = mesh.find("strain_min")) m.strain_min = f->nonNegative();
      if (auto f = mesh.find("strain_max")) m.strain_max = f->nonNegative();
      if (auto f = mesh.find("hinge_stiffness")) m.hinge_stiffness = f->nonNegative();
      out = loadObjCloth(path.string(), m);
    } else {
      std::set<std::string> keys = common;
      keys.insert({"density", "stiffness"});
      mesh.allowOnly(keys);
      SolidMaterial m;
      if (auto f = mesh.find("density")) m.density = f->positive();
      if (auto f = mesh.find("stiffness")) m.stiffness = f->nonNegative();
      if (type == "medit") {
        out = loadMedit(path.string(), m);
      } else {
        const std::string ext = lowerExtension(path);
        fs::path base = path;
        if (ext == ".node" || ext == ".ele") base.replace_extension();
        out = loadTetGen(base.string(), m);
      }
    }
  } catch (const FileFormatError& e) {
    // The mesh file's own error (file and line) inside the scene file's context.
    file_field.fail(e.what());
  }
  if (auto f = mesh.find("damping")) {
    const double d = f->number();
    if (d < 0.0 || d > 1.0) f->fail("must be in [0, 1], got " + Field::text(d));
    for (Body& b : out.bodies) b.damping = d;
  }
  if (auto f = mesh.find("name")) {
    out.name = f->string();
    for (Body& b : out.bodies) b.name = out.name;
  }
  return out;
}

// --- assembling parts ------------------------------------------------------------------------------

template <typename Matrix>
void appendRows(Matrix& into, const Matrix& rows) {
  const Eigen::Index n = into.rows();
  into.conservativeResize(n + rows.rows(), Eigen::NoChange);
  into.bottomRows(rows.rows()) = rows;
}

void translate(Scene& s, const Eigen::Vector3d& t) {
  s.positions.rowwise() += t.transpose();
  s.rest_positions.rowwise() += t.transpose();
  for (Pin& pin : s.pins) pin.target.position += t;
}

// Calls `each` for the object, or for every object of the array, under `key`.
template <typename Each>
void forEachEntry(const Field& root, const std::string& key, Each each) {
  auto f = root.find(key);
  if (!f) return;
  if (f->value().is_array()) {
    for (size_t i = 0; i < f->size(); ++i) each((*f)[i]);
  } else {
    f->requireObject();
    each(*f);
  }
}

Eigen::MatrixX3d readRows(const Field& f) {
  Eigen::MatrixX3d m(f.size(), 3);
  for (size_t i = 0; i < f.size(); ++i) m.row(i) = f[i].vector3().transpose();
  return m;
}

// Explicit particles: appended after the builtin and mesh parts. Masses are read later, once
// the tets and triangles that may lump them are known.
void readParticles(const Field& block, Scene& s) {
  block.allowOnly({"positions", "rest_positions", "velocities", "masses", "density", "areal_density"});
  const Eigen::MatrixX3d x = readRows(block.member("positions"));
  const auto sameRows = [&](const char* key) -> Eigen::MatrixX3d {
    auto f = block.find(key);
    if (!f) return key == std::string("velocities") ? Eigen::MatrixX3d::Zero(x.rows(), 3) : x;
    Eigen::MatrixX3d m = readRows(*f);
    if (m.rows() != x.rows()) {
      f->fail("has " + std::to_string(m.rows()) + " rows, expected " + std::to_string(x.rows()) +
              " (one per position)");
    }
    return m;
  };
  appendRows(s.positions, x);
  appendRows(s.rest_positions, sameRows("rest_positions"));
  appendRows(s.velocities, sameRows("velocities"));
}

// `first` is the first explicit particle; the top-level tets are s.tets from `first_tet` on.
void readMasses(const Field& root, const Field& block, Scene& s, int first, std::size_t first_tet,
                const std::vector<std::array<int, 3>>& triangles) {
  const int count = s.numParticles() - first;
  s.masses.conservativeResize(s.numParticles());
  const bool by_density = block.has("density") || block.has("areal_density");
  if (auto f = block.find("masses")) {
    if (by_density) f->fail("give either masses or density/areal_density, not both");
    if (f->value().is_number()) {
      s.masses.tail(count).setConstant(f->positive());
    } else {
      if (static_cast<int>(f->size()) != count) {
        f->fail("has " + std::to_string(f->size()) + " entries, expected " + std::to_string(count) +
                " (one per position)");
      }
      for (int i = 0; i < count; ++i) s.masses[first + i] = (*f)[i].positive();
    }
    return;
  }
  if (!by_density) block.fail("needs masses, or density (tets) / areal_density (triangles) to lump them");
  // Only the top-level tets and triangles can reach explicit particles; a share that overflows
  // is named by its element's path.
  Eigen::VectorXd lumped = Eigen::VectorXd::Zero(s.numParticles());
  if (auto f = block.find("density")) {
    const std::vector<Tet> tets(s.tets.begin() + static_cast<std::ptrdiff_t>(first_tet), s.tets.end());
    if (const auto failure = lumping::addTets(s.rest_positions, tets, f->positive(), "density", lumped)) {
      root.member("tets")[failure->element].fail(failure->what);
    }
  }
  if (auto f = block.find("areal_density")) {
    if (const auto failure =
            lumping::addTriangles(s.rest_positions, triangles, f->positive(), "areal_density", lumped)) {
      root.member("triangles")[failure->element].fail(failure->what);
    }
  }
  for (int i = 0; i < count; ++i) {
    if (!(lumped[first + i] > 0.0)) {
      block.fail("particle " + std::to_string(first + i) +
                 " gets no mass from density/areal_density (it is in no tet or triangle); give masses instead");
    }
  }
  s.masses.tail(count) = lumped.tail(count);
}

// A region of the rest shape: {"axis": "x", "min": a, "max": b} (a slab; either bound may be
// left out) or {"min": [x, y, z], "max": [x, y, z]} (a box). Bounds are inclusive.
std::vector<int> selectWhere(const Field& where, const Scene& s) {
  where.requireObject();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(-INFINITY), hi = Eigen::Vector3d::Constant(INFINITY);
  if (auto axis = where.find("axis")) {
    where.allowOnly({"axis", "min", "max"});
    const std::string name = axis->string();
    if (name != "x" && name != "y" && name != "z")
      axis->fail("expected \"x\", \"y\" or \"z\", got \"" + shown(name) + "\"");
    const int c = name[0] - 'x';
    if (!where.has("min") && !where.has("max")) where.fail("needs min, max or both");
    if (auto f = where.find("min")) lo[c] = f->number();
    if (auto f = where.find("max")) hi[c] = f->number();
  } else {
    where.allowOnly({"min", "max"});
    if (!where.has("min") && !where.has("max")) where.fail("needs \"axis\" with min/max, or min/max corners [x, y, z]");
    if (auto f = where.find("min")) lo = f->vector3();
    if (auto f = where.find("max")) hi = f->vector3();
  }
  std::vector<int> selected;
  for (int j = 0; j < s.numParticles(); ++j) {
    const Eigen::Vector3d x = s.rest_positions.row(j).transpose();
    if ((x.array() >= lo.array()).all() && (x.array() <= hi.array()).all()) selected.push_back(j);
  }
  if (selected.empty()) where.fail("selects no particle (bounds are compared with the rest positions)");
  return selected;
}

// "particles": [..] or "where": {..}; neither: every particle.
std::vector<int> readSelection(const Field& entry, const Scene& s, bool& given) {
  auto list = entry.find("particles");
  auto where = entry.find("where");
  given = list || where;
  if (list && where) where->fail("give either particles or where, not both");
  if (list) return list->particles(s.numParticles());
  if (where) return selectWhere(*where, s);
  return {};
}

Eigen::Vector3d vectorOr(const Field& entry, const char* key) {
  auto f = entry.find(key);
  return f ? f->vector3() : Eigen::Vector3d::Zero();
}

double frequencyOf(const Field& entry) {
  auto f = entry.find("frequency");
  return f ? f->number() : 0.0;
}

void readSprings(const Field& list, Scene& s) {
  const int n = s.numParticles();
  for (size_t i = 0; i < list.size(); ++i) {
    const Field e = list[i];
    e.allowOnly({"a", "b", "stiffness", "rest_length"});
    Spring sp;
    sp.a = e.member("a").particle(n);
    sp.b = e.member("b").particle(n);
    if (sp.a == sp.b) e.member("b").fail("spring joins particle " + std::to_string(sp.a) + " to itself");
    sp.stiffness = e.member("stiffness").nonNegative();
    auto rest = e.find("rest_length");
    sp.rest_length = rest ? rest->nonNegative() : (s.rest_positions.row(sp.a) - s.rest_positions.row(sp.b)).norm();
    s.springs.push_back(sp);
  }
}

void readTets(const Field& list, Scene& s) {
  const int n = s.numParticles();
  for (size_t i = 0; i < list.size(); ++i) {
    const Field e = list[i];
    e.allowOnly({"vertices", "stiffness"});
    const Field v = e.member("vertices");
    if (v.size() != 4) v.fail("expected 4 particle indices, got " + std::to_string(v.size()));
    Tet tet;
    for (int k = 0; k < 4; ++k) tet.vertices[k] = v[k].particle(n);
    tet.stiffness = e.member("stiffness").nonNegative();
    // The test validation applies to every tet, here to name the field.
    const validation::RestShape shape = validation::restTet(s.rest_positions, tet.vertices);
    if (!shape.fine()) v.fail(validation::restShapeProblem(shape));
    if (shape.measure < 0.0) {
      v.fail("rest volume " + Field::text(shape.measure) +
             " is not positive (inverted: list two vertices in the other order)");
    }
    s.tets.push_back(tet);
  }
}

std::vector<std::array<int, 3>> readTriangles(const Field& list, int n) {
  std::vector<std::array<int, 3>> triangles(list.size());
  for (size_t i = 0; i < list.size(); ++i) {
    const Field t = list[i];
    if (t.size() != 3) t.fail("expected 3 particle indices, got " + std::to_string(t.size()));
    for (int k = 0; k < 3; ++k) triangles[i][k] = t[k].particle(n);
  }
  return triangles;
}

// The generic JSON form of an element type: {"vertices": [...], <field>: number, ...}.
void readGenericElements(const ElementType& type, const Field& list, Scene& s) {
  const int n = s.numParticles();
  const std::vector<ElementType::Field> fields = type.jsonFields();
  std::set<std::string> keys = {"vertices"};
  for (const auto& f : fields) keys.insert(f.key);
  const size_t k = size_t(type.shape().vertices);
  std::vector<int> vertices(k);
  std::vector<double> values(fields.size());
  for (size_t i = 0; i < list.size(); ++i) {
    const Field e = list[i];
    e.allowOnly(keys);
    const Field v = e.member("vertices");
    if (v.size() != k) v.fail("expected " + std::to_string(k) + " particle indices, got " + std::to_string(v.size()));
    for (size_t j = 0; j < k; ++j) vertices[j] = v[j].particle(n);
    for (size_t j = 0; j < fields.size(); ++j) {
      auto f = fields[j].required ? std::optional<Field>(e.member(fields[j].key)) : e.find(fields[j].key);
      values[j] = f ? f->number() : fields[j].default_value;
    }
    type.appendRecord(s, vertices, values);
  }
}

// JSON key of a type with a generic form: its identifier, plural ("triangle_strains").
std::string genericKey(const ElementType& type) { return std::string(type.identifier()) + "s"; }

std::vector<const ElementType*> genericTypes() {
  std::vector<const ElementType*> out;
  for (const ElementType* type : elementTypes()) {
    if (!type->jsonFields().empty()) out.push_back(type);
  }
  return out;
}

PinTarget readTarget(const Field& target, bool allow_position, const Eigen::Vector3d& default_position) {
  target.allowOnly({"position", "velocity", "amplitude", "frequency"});
  PinTarget t;
  t.position = default_position;
  if (auto f = target.find("position")) {
    if (!allow_position) f->fail("not allowed with pin_where: each pin targets its own particle's rest position");
    t.position = f->vector3();
  }
  t.velocity = vectorOr(target, "velocity");
  t.amplitude = vectorOr(target, "amplitude");
  t.frequency = frequencyOf(target);
  return t;
}

void readPins(const Field& list, Scene& s) {
  const int n = s.numParticles();
  for (size_t i = 0; i < list.size(); ++i) {
    const Field e = list[i];
    e.allowOnly({"vertex", "pin_where", "stiffness", "target"});
    const double k = e.member("stiffness").nonNegative();
    auto vertex = e.find("vertex");
    auto where = e.find("pin_where");
    if (vertex && where) where->fail("give either vertex or pin_where, not both");
    if (!vertex && !where) e.fail("needs vertex or pin_where");
    auto target = e.find("target");
    if (vertex) {
      Pin pin;
      pin.vertex = vertex->particle(n);
      pin.stiffness = k;
      const Eigen::Vector3d rest = s.rest_positions.row(pin.vertex).transpose();
      pin.target = target ? readTarget(*target, true, rest) : PinTarget{rest};
      s.pins.push_back(pin);
    } else {
      for (int j : selectWhere(*where, s)) {
        Pin pin;
        pin.vertex = j;
        pin.stiffness = k;
        const Eigen::Vector3d rest = s.rest_positions.row(j).transpose();
        pin.target = target ? readTarget(*target, false, rest) : PinTarget{rest};
        s.pins.push_back(pin);
      }
    }
  }
}

void readForceFields(const Field& list, Scene& s) {
  for (size_t i = 0; i < list.size(); ++i) {
    const Field e = list[i];
    e.allowOnly({"particles", "where", "force", "rate", "amplitude", "frequency"});
    ForceField f;
    bool given = false;
    f.particles = readSelection(e, s, given);
    f.force = vectorOr(e, "force");
    f.rate = vectorOr(e, "rate");
    f.amplitude = vectorOr(e, "amplitude");
    f.frequency = frequencyOf(e);
    s.force_fields.push_back(std::move(f));
  }
}

void readBodies(const Field& list, Scene& s) {
  for (size_t i = 0; i < list.size(); ++i) {
    const Field e = list[i];
    e.allowOnly({"name", "particles", "where", "damping"});
    Body b;
    if (auto f = e.find("name")) b.name = f->string();
    bool given = false;
    b.particles = readSelection(e, s, given);
    if (!given) {
      b.particles.resize(s.numParticles());
      for (int j = 0; j < s.numParticles(); ++j) b.particles[j] = j;
    }
    if (auto f = e.find("damping")) {
      b.damping = f->number();
      if (b.damping < 0.0 || b.damping > 1.0) f->fail("must be in [0, 1], got " + Field::text(b.damping));
    }
    s.bodies.push_back(std::move(b));
  }
}

// Colliders (docs/scene-format.md): {"shape": "plane" | "sphere" | "box" | "capsule", "center",
// the shape's own fields (normal; radius; half_extents; end, radius), and optionally velocity,
// friction and stiffness}; the values are checked by validateScene.
const char* const kColliderShapes[] = {"plane", "sphere", "box", "capsule"};

void readColliders(const Field& list, Scene& s) {
  for (size_t i = 0; i < list.size(); ++i) {
    const Field e = list[i];
    e.allowOnly({"shape", "center", "normal", "radius", "half_extents", "end", "velocity", "friction", "stiffness"});
    Collider c;
    const Field shape = e.member("shape");
    const std::string name = shape.string();
    const auto* found = std::find(std::begin(kColliderShapes), std::end(kColliderShapes), name);
    if (found == std::end(kColliderShapes))
      shape.fail("unknown collider shape \"" + shown(name) + "\" (plane, sphere, box or capsule)");
    c.shape = static_cast<ColliderShape>(found - std::begin(kColliderShapes));
    c.center = vectorOr(e, "center");
    if (auto f = e.find("normal")) c.normal = f->vector3();
    if (auto f = e.find("radius")) c.radius = f->number();
    if (auto f = e.find("half_extents")) c.half_extents = f->vector3();
    if (auto f = e.find("end")) c.end = f->vector3();
    c.velocity = vectorOr(e, "velocity");
    if (auto f = e.find("friction")) c.friction = f->number();
    if (auto f = e.find("stiffness")) c.stiffness = f->number();
    s.colliders.push_back(c);
  }
}

Scene sceneFromJson(const json& doc, const std::string& file) {
  const Field root(doc, "", file);
  root.requireObject();
  std::set<std::string> keys = {"format", "version",      "name",      "gravity",   "builtin",
                                "mesh",   "particles",    "triangles", "springs",   "tets",
                                "pins",   "force_fields", "bodies",    "colliders", "events"};
  for (const ElementType* type : genericTypes()) keys.insert(genericKey(*type));
  root.allowOnly(keys);
  if (auto f = root.find("format")) {
    if (f->string() != kFormatName)
      f->fail("expected \"" + std::string(kFormatName) + "\", got \"" + shown(f->string()) + "\"");
  }
  if (auto f = root.find("version")) {
    if (f->integer() != kFormatVersion) {
      f->fail("unsupported version " + std::to_string(f->integer()) + " (this library reads version " +
              std::to_string(kFormatVersion) + ")");
    }
  }
  const fs::path dir = fs::path(file).parent_path();

  Scene s;
  int parts = 0;
  std::string part_name;
  std::optional<Eigen::Vector3d> part_gravity;
  const auto addPart = [&](Scene part, const Field& entry) {
    if (auto t = entry.find("translate")) translate(part, t->vector3());
    ++parts;
    part_name = part.name;
    if (!part_gravity) part_gravity = part.gravity;
    appendScene(s, part);
  };
  forEachEntry(root, "builtin", [&](const Field& entry) {
    const Field name = entry.member("name");
    addPart(builtinFromField(name.string(), entry, {"name", "translate"}, name), entry);
  });
  forEachEntry(root, "mesh", [&](const Field& entry) { addPart(meshFromField(entry, dir), entry); });

  const int first_explicit = s.numParticles();
  auto block = root.find("particles");
  if (block) {
    block->requireObject();
    readParticles(*block, s);
  }
  if (s.numParticles() == 0) root.fail("no particles: give particles, builtin or mesh");

  std::vector<std::array<int, 3>> explicit_triangles;
  if (auto f = root.find("triangles")) explicit_triangles = readTriangles(*f, s.numParticles());
  const std::size_t first_tet = s.tets.size();
  if (auto f = root.find("tets")) readTets(*f, s);
  if (block) readMasses(root, *block, s, first_explicit, first_tet, explicit_triangles);
  s.triangles.insert(s.triangles.end(), explicit_triangles.begin(), explicit_triangles.end());
  if (auto f = root.find("springs")) readSprings(*f, s);
  for (const ElementType* type : genericTypes()) {
    if (auto f = root.find(genericKey(*type))) readGenericElements(*type, *f, s);
  }
  if (auto f = root.find("pins")) readPins(*f, s);
  if (auto f = root.find("force_fields")) readForceFields(*f, s);
  if (auto f = root.find("bodies")) readBodies(*f, s);
  if (auto f = root.find("colliders")) readColliders(*f, s);

  if (auto f = root.find("gravity")) {
    s.gravity = f->vector3();
  } else {
    s.gravity = part_gravity.value_or(Scene().gravity);
  }
  if (auto f = root.find("name")) {
    s.name = f->string();
  } else {
    s.name = (parts == 1 && !block) ? part_name : sceneNameFromPath(file);
  }
  try {
    validateScene(s);
  } catch (const InvalidInputError& e) {
    root.fail(e.what());
  }
  return s;
}

// Deepest nesting of arrays and objects a scene file may have (a scene needs 4 levels). The
// parser copes with any depth, but code that walks a value recursively does not: 70,000 levels
// overflowed the stack. Scanned before parsing, so that the error has a line.
constexpr int kMaxJsonDepth = 64;

void checkNesting(const std::string& text, const std::string& file) {
  int depth = 0, line = 1;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') ++line;
    if (in_string) {
      if (c == '\\' && i + 1 < text.size() && text[i + 1] != '\n')
        ++i;  // an escaped quote ends nothing
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth) {
        throw FileFormatError(file, line, "JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
      }
    } else if (c == ']' || c == '}') {
      --depth;  // unbalanced brackets are the parser's to report
    }
  }
}

// A key given twice in one object: the JSON library keeps the last one silently, so a scene
// would run with a value the reader of the file may not have seen, although every key is
// promised to be checked. Scanned after a successful parse, when the text is known to be valid
// JSON: a string right after '{' or after ',' in an object is a key. Keys are compared decoded
// ("a" and "\u0061" are the same key).
void checkDuplicateKeys(const std::string& text, const std::string& file) {
  struct Container {
    bool object;
    std::map<std::string, int> keys;  // key -> line of its first occurrence
  };
  std::vector<Container> open;
  bool expect_key = false;
  int line = 1;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
    } else if (c == '{' || c == '[') {
      open.push_back({c == '{', {}});
      expect_key = c == '{';
    } else if (c == '}' || c == ']') {
      if (!open.empty()) open.pop_back();  // valid JSON is balanced; never trust it past that
      expect_key = false;
    } else if (c == ',') {
      expect_key = !open.empty() && open.back().object;
    } else if (c == '"') {
      const std::size_t start = i;
      bool escaped = false;
      for (++i; i < text.size() && text[i] != '"'; ++i) {
        if (text[i] == '\\') escaped = true, ++i;  // valid JSON: the escape is complete
      }
      if (i >= text.size()) return;  // an unterminated string: the parser's to report
      if (!expect_key || open.empty()) continue;
      expect_key = false;
      std::string key = text.substr(start + 1, i - start - 1);
      if (escaped) key = json::parse(text.substr(start, i - start + 1)).get<std::string>();
      const auto [first, inserted] = open.back().keys.emplace(key, line);
      if (!inserted) {
        throw FileFormatError(file, line,
                              "duplicate key '" + shown(key) + "' (first on line " + std::to_string(first->second) +
                                  "): one of them would be ignored");
      }
    }
  }
}

// The JSON library ends its input at a NUL byte and reports success, so whatever follows one
// would be ignored (and the key scan below would read it as JSON): a NUL is refused.
void checkNoNul(const std::string& text, const std::string& file) {
  const std::size_t at = text.find('\0');
  if (at == std::string::npos) return;
  const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
  throw FileFormatError(file, line, "NUL byte at offset " + std::to_string(at) + ": not a JSON text");
}

json parseJson(const std::string& text, const std::string& file) {
  checkNoNul(text, file);
  checkNesting(text, file);
  try {
    json doc = json::parse(text);
    checkDuplicateKeys(text, file);
    return doc;
  } catch (const json::parse_error& e) {
    // e.byte is the 1-based offset of the offending character; report line and column.
    const size_t end = std::min<size_t>(e.byte == 0 ? 0 : e.byte - 1, text.size());
    int line = 1;
    size_t line_start = 0;
    for (size_t i = 0; i < end; ++i) {
      if (text[i] == '\n') {
        ++line;
        line_start = i + 1;
      }
    }
    std::string what = e.what();
    const size_t column_at = what.find("column");
    const size_t colon = column_at == std::string::npos ? std::string::npos : what.find(": ", column_at);
    if (colon != std::string::npos) what = what.substr(colon + 2);
    // The message quotes what was last read, raw bytes included.
    throw FileFormatError(file, line,
                          "malformed JSON (column " + std::to_string(end - line_start + 1) + "): " + shown(what, 400));
  } catch (const json::exception& e) {
    // Number overflow ("1e999") comes without a position.
    std::string what = e.what();
    const size_t bracket = what.find("] ");
    if (bracket != std::string::npos) what = what.substr(bracket + 2);
    throw FileFormatError(file, 0, "malformed JSON: " + shown(what, 400));
  }
}

// --- writing --------------------------------------------------------------------------------------

using ordered = nlohmann::ordered_json;

ordered vec(const Eigen::Vector3d& v) { return ordered::array({v.x(), v.y(), v.z()}); }

ordered rows(const Eigen::MatrixX3d& m) {
  ordered a = ordered::array();
  for (Eigen::Index i = 0; i < m.rows(); ++i) a.push_back(ordered::array({m(i, 0), m(i, 1), m(i, 2)}));
  return a;
}

bool bitwiseEqual(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  return a.rows() == b.rows() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

// +0.0 only: a -0.0 must be written to come back as -0.0.
bool plainZero(double x) { return x == 0.0 && !std::signbit(x); }

template <typename Derived>
bool plainZero(const Eigen::DenseBase<Derived>& m) {
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    for (Eigen::Index j = 0; j < m.cols(); ++j) {
      if (!plainZero(static_cast<double>(m(i, j)))) return false;
    }
  }
  return true;
}

// One item per line once a container no longer fits on one: readable and diff-friendly for
// lists of particles and springs, compact for vectors.
void pretty(std::string& out, const ordered& v, int indent) {
  const std::string flat = v.dump();
  if (!v.is_structured() || v.empty() || flat.size() + indent <= 100) {
    out += flat;
    return;
  }
  out += v.is_object() ? "{\n" : "[\n";
  bool first = true;
  for (auto it = v.begin(); it != v.end(); ++it) {
    if (!first) out += ",\n";
    first = false;
    out.append(indent + 2, ' ');
    if (v.is_object()) out += ordered(it.key()).dump() + ": ";
    pretty(out, it.value(), indent + 2);
  }
  out += '\n';
  out.append(indent, ' ');
  out += v.is_object() ? '}' : ']';
}

ordered sceneToJson(const Scene& s) {
  ordered doc;
  doc["format"] = kFormatName;
  doc["version"] = kFormatVersion;
  doc["name"] = s.name;
  doc["gravity"] = vec(s.gravity);
  ordered particles;
  particles["positions"] = rows(s.positions);
  if (!bitwiseEqual(s.rest_positions, s.positions)) particles["rest_positions"] = rows(s.rest_positions);
  if (!plainZero(s.velocities)) particles["velocities"] = rows(s.velocities);
  particles["masses"] = ordered(std::vector<double>(s.masses.data(), s.masses.data() + s.masses.size()));
  doc["particles"] = std::move(particles);
  if (!s.springs.empty()) {
    ordered a = ordered::array();
    for (const Spring& sp : s.springs) {
      a.push_back({{"a", sp.a}, {"b", sp.b}, {"stiffness", sp.stiffness}, {"rest_length", sp.rest_length}});
    }
    doc["springs"] = std::move(a);
  }
  if (!s.tets.empty()) {
    ordered a = ordered::array();
    for (const Tet& t : s.tets) {
      a.push_back(
          {{"vertices", ordered(std::vector<int>(t.vertices.begin(), t.vertices.end()))}, {"stiffness", t.stiffness}});
    }
    doc["tets"] = std::move(a);
  }
  for (const ElementType* type : genericTypes()) {
    if (type->count(s) == 0) continue;
    const std::vector<ElementType::Field> fields = type->jsonFields();
    ordered a = ordered::array();
    std::vector<int> vertices;
    std::vector<double> values;
    for (int i = 0; i < type->count(s); ++i) {
      type->record(s, i, vertices, values);
      ordered e;
      e["vertices"] = vertices;
      for (size_t j = 0; j < fields.size(); ++j) e[fields[j].key] = values[j];
      a.push_back(std::move(e));
    }
    doc[genericKey(*type)] = std::move(a);
  }
  if (!s.pins.empty()) {
    ordered a = ordered::array();
    for (const Pin& p : s.pins) {
      ordered target = {{"position", vec(p.target.position)}};
      if (!plainZero(p.target.velocity) || !plainZero(p.target.amplitude) || !plainZero(p.target.frequency)) {
        target["velocity"] = vec(p.target.velocity);
        target["amplitude"] = vec(p.target.amplitude);
        target["frequency"] = p.target.frequency;
      }
      a.push_back({{"vertex", p.vertex}, {"stiffness", p.stiffness}, {"target", std::move(target)}});
    }
    doc["pins"] = std::move(a);
  }
  if (!s.force_fields.empty()) {
    ordered a = ordered::array();
    for (const ForceField& f : s.force_fields) {
      ordered e;
      if (!f.particles.empty()) e["particles"] = f.particles;
      e["force"] = vec(f.force);
      e["rate"] = vec(f.rate);
      e["amplitude"] = vec(f.amplitude);
      e["frequency"] = f.frequency;
      a.push_back(std::move(e));
    }
    doc["force_fields"] = std::move(a);
  }
  if (!s.colliders.empty()) {
    ordered a = ordered::array();
    for (const Collider& c : s.colliders) {
      ordered e;
      e["shape"] = kColliderShapes[static_cast<int>(c.shape)];  // validated by saveSceneFile
      e["center"] = vec(c.center);
      if (c.shape == ColliderShape::Plane) e["normal"] = vec(c.normal);
      if (c.shape == ColliderShape::Box) e["half_extents"] = vec(c.half_extents);
      if (c.shape == ColliderShape::Capsule) e["end"] = vec(c.end);
      if (c.shape == ColliderShape::Sphere || c.shape == ColliderShape::Capsule) e["radius"] = c.radius;
      if (c.moving()) e["velocity"] = vec(c.velocity);
      e["friction"] = c.friction;
      e["stiffness"] = c.stiffness;
      a.push_back(std::move(e));
    }
    doc["colliders"] = std::move(a);
  }
  if (!s.bodies.empty()) {
    ordered a = ordered::array();
    for (const Body& b : s.bodies) {
      a.push_back({{"name", b.name}, {"damping", b.damping}, {"particles", b.particles}});
    }
    doc["bodies"] = std::move(a);
  }
  if (!s.triangles.empty()) {
    ordered a = ordered::array();
    for (const auto& t : s.triangles) a.push_back(ordered::array({t[0], t[1], t[2]}));
    doc["triangles"] = std::move(a);
  }
  return doc;
}

// --- scripted events (include/stabint/events.hpp) --------------------------------------------------
// {"frame": f, "<kind>": {...}}: one action per event. A new kind of event adds a key here, in
// eventToJson, and a case in EventScript::apply.

// An element list index of `kind` in scene `s`.
int elementCount(const Scene& s, ElementKind kind) {
  switch (kind) {
    case ElementKind::Spring: return static_cast<int>(s.springs.size());
    case ElementKind::Tet: return static_cast<int>(s.tets.size());
    case ElementKind::TriangleStrain: return static_cast<int>(s.triangle_strains.size());
    case ElementKind::BendingHinge: return static_cast<int>(s.bending_hinges.size());
    case ElementKind::Pin: return static_cast<int>(s.pins.size());
  }
  return 0;
}

// A path: keyframes [frame, x, y, z] with frames increasing after the event's (`owner`'s).
std::vector<PathKey> readPath(const Field& path, int frame, const char* owner) {
  std::vector<PathKey> keys;
  int last = frame;
  for (size_t i = 0; i < path.size(); ++i) {
    const Field key = path[i];
    if (!key.value().is_array() || key.size() != 4) key.fail("expected a keyframe [frame, x, y, z]");
    PathKey k;
    k.frame = key[0].integer();
    if (k.frame <= last)
      key[0].fail("keyframe frame " + std::to_string(k.frame) + " must be after " + std::to_string(last) +
                  (i == 0 ? " (" + std::string(owner) + " frame)" : std::string(" (the previous keyframe's)")));
    last = k.frame;
    k.position = Eigen::Vector3d(key[1].eventValue(), key[2].eventValue(), key[3].eventValue());
    keys.push_back(k);
  }
  return keys;
}

GrabEvent readGrab(const Field& f, const Scene& s, int frame) {
  f.allowOnly({"id", "vertex", "stiffness", "path"});
  GrabEvent g;
  if (auto id = f.find("id")) g.id = id->string();
  g.vertex = f.member("vertex").particle(s.numParticles());
  const Field stiffness = f.member("stiffness");
  stiffness.eventValue();  // within 1e150
  g.stiffness = stiffness.positive();
  if (auto path = f.find("path")) g.path = readPath(*path, frame, "the grab's");
  return g;
}

ReleaseEvent readRelease(const Field& f, const Scene& s) {
  ReleaseEvent r;
  if (f.value().is_string()) {
    r.id = f.string();
  } else if (f.value().is_number()) {
    r.vertex = f.particle(s.numParticles());
  } else {
    f.fail(std::string("expected a grab's id (string) or a vertex (integer), got ") + f.value().type_name());
  }
  return r;
}

ImpulseEvent readImpulse(const Field& f, const Scene& s) {
  f.allowOnly({"vertices", "where", "velocity"});
  ImpulseEvent im;
  auto list = f.find("vertices");
  auto where = f.find("where");
  if (list && where) where->fail("give either vertices or where, not both");
  if (!list && !where) f.fail("needs vertices or where");
  im.vertices = list ? list->particles(s.numParticles()) : selectWhere(*where, s);
  if (im.vertices.empty()) list->fail("lists no vertex");
  im.velocity = f.member("velocity").eventVector();
  return im;
}

ElementEvent readElements(const Field& f, const Scene& s) {
  f.allowOnly({"kind", "indices", "stiffness", "enabled"});
  ElementEvent e;
  const Field kind = f.member("kind");
  try {
    e.kind = parseElementKind(kind.string());
  } catch (const InvalidInputError& error) {
    kind.fail(error.what());
  }
  const Field indices = f.member("indices");
  const int count = elementCount(s, e.kind);
  for (size_t i = 0; i < indices.size(); ++i) {
    const int index = indices[i].integer();
    if (index < 0 || index >= count)
      indices[i].fail(std::string(elementKindName(e.kind)) + " " + std::to_string(index) + " out of range [0, " +
                      std::to_string(count) + ")");
    e.indices.push_back(index);
  }
  if (e.indices.empty()) indices.fail("lists no element");
  if (auto k = f.find("stiffness")) {
    k->eventValue();  // within 1e150
    e.stiffness = k->nonNegative();
  }
  if (auto on = f.find("enabled")) {
    if (!on->value().is_boolean()) on->fail(std::string("expected true or false, got ") + on->value().type_name());
    e.enabled = on->value().get<bool>();
  }
  if (!e.stiffness && !e.enabled) f.fail("needs stiffness, enabled or both");
  return e;
}

ColliderEvent readColliderEvent(const Field& f, const Scene& s, int frame) {
  f.allowOnly({"index", "path", "velocity"});
  ColliderEvent c;
  const Field index = f.member("index");
  c.collider = index.integer();
  const int count = static_cast<int>(s.colliders.size());
  if (c.collider < 0 || c.collider >= count)
    index.fail("collider " + std::to_string(c.collider) + " out of range [0, " + std::to_string(count) + ")");
  auto path = f.find("path");
  auto velocity = f.find("velocity");
  if (path && velocity) velocity->fail("give either path or velocity, not both");
  if (!path && !velocity) f.fail("needs path or velocity");
  if (path) {
    c.path = readPath(*path, frame, "the event's");
    if (c.path.empty()) path->fail("lists no keyframe");
  } else {
    c.velocity = velocity->eventVector();
  }
  return c;
}

// The "events" list of a scene file, against its scene `s` (indices in range, "where" selected
// on its rest shape); the ordering rules are EventScript's, reported at the event's path.
EventScript readEvents(const Field& list, const Scene& s) {
  std::vector<ScriptedEvent> events;
  for (size_t i = 0; i < list.size(); ++i) {
    const Field entry = list[i];
    entry.allowOnly({"frame", "grab", "release", "impulse", "elements", "collider"});
    ScriptedEvent ev;
    const Field frame = entry.member("frame");
    ev.frame = frame.integer();
    if (ev.frame < 0) frame.fail("must be >= 0, got " + std::to_string(ev.frame));
    int actions = 0;
    if (auto f = entry.find("grab")) ev.action = readGrab(*f, s, ev.frame), ++actions;
    if (auto f = entry.find("release")) ev.action = readRelease(*f, s), ++actions;
    if (auto f = entry.find("impulse")) ev.action = readImpulse(*f, s), ++actions;
    if (auto f = entry.find("elements")) ev.action = readElements(*f, s), ++actions;
    if (auto f = entry.find("collider")) ev.action = readColliderEvent(*f, s, ev.frame), ++actions;
    if (actions != 1) entry.fail("needs exactly one of grab, release, impulse, elements, collider");
    events.push_back(std::move(ev));
  }
  try {
    return EventScript(std::move(events));
  } catch (const InvalidInputError& e) {
    list.fail(e.what());
  }
}

ordered pathToJson(const std::vector<PathKey>& keys) {
  ordered path = ordered::array();
  for (const PathKey& k : keys)
    path.push_back(
        ordered::array({ordered(k.frame), ordered(k.position.x()), ordered(k.position.y()), ordered(k.position.z())}));
  return path;
}

ordered eventToJson(const ScriptedEvent& ev) {
  ordered e;
  e["frame"] = ev.frame;
  if (const auto* g = std::get_if<GrabEvent>(&ev.action)) {
    ordered grab;
    if (!g->id.empty()) grab["id"] = g->id;
    grab["vertex"] = g->vertex;
    grab["stiffness"] = g->stiffness;
    if (!g->path.empty()) grab["path"] = pathToJson(g->path);
    e["grab"] = std::move(grab);
  } else if (const auto* r = std::get_if<ReleaseEvent>(&ev.action)) {
    e["release"] = r->id.empty() ? ordered(r->vertex) : ordered(r->id);
  } else if (const auto* im = std::get_if<ImpulseEvent>(&ev.action)) {
    e["impulse"] = {{"vertices", im->vertices}, {"velocity", vec(im->velocity)}};
  } else if (const auto* el = std::get_if<ElementEvent>(&ev.action)) {
    ordered elements;
    elements["kind"] = elementKindName(el->kind);
    elements["indices"] = el->indices;
    if (el->stiffness) elements["stiffness"] = *el->stiffness;
    if (el->enabled) elements["enabled"] = *el->enabled;
    e["elements"] = std::move(elements);
  } else if (const auto* c = std::get_if<ColliderEvent>(&ev.action)) {
    ordered collider;
    collider["index"] = c->collider;
    if (c->velocity) {
      collider["velocity"] = vec(*c->velocity);
    } else {
      collider["path"] = pathToJson(c->path);
    }
    e["collider"] = std::move(collider);
  }
  return e;
}

}  // namespace

}  // namespace stabint::io

namespace stabint {

using io::Field;
using io::json;

Scene builtinScene(const std::string& name, const std::string& params_json, const std::string& label) {
  const json params = io::parseJson(params_json.empty() ? "{}" : params_json, label);
  const json name_value = name;
  const Field root(params, "params", label);
  root.requireObject();
  return io::builtinFromField(name, root, {}, Field(name_value, "name", label));
}

std::vector<std::string> builtinSceneNames() { return {"oscillator", "chain", "cloth", "tetbar"}; }

std::vector<std::string> builtinSceneParameters(const std::string& name) {
  using namespace io;
  std::vector<std::string> names;
  const ParamNames collect{names};
  if (name == "oscillator") {
    LinearOscillatorParams p;
    visitParams(collect, p);
  } else if (name == "chain") {
    ChainPendulumParams p;
    visitParams(collect, p);
  } else if (name == "cloth") {
    ClothGridParams p;
    visitParams(collect, p);
  } else if (name == "tetbar") {
    TetBarParams p;
    visitParams(collect, p);
  }
  return names;
}

namespace {

// The text of a scene file: the scene's explicit form, then the events (validated by
// EventScript; here only against the scene's ranges, as the reader checks them).
void saveSceneText(const Scene& scene, const EventScript* events, std::string& text) {
  validateScene(scene);
  // A scene file is UTF-8 text; other bytes in a name made the JSON library throw its own type.
  const auto requireUtf8 = [](const std::string& name, const std::string& field) {
    const std::size_t bad = io::invalidUtf8At(name);
    if (bad != std::string::npos) {
      throw InvalidInputError(field + " '" + io::shown(name) + "' is not valid UTF-8 (byte " + std::to_string(bad + 1) +
                              "); a scene file holds UTF-8 text");
    }
  };
  requireUtf8(scene.name, "scene name");
  for (std::size_t i = 0; i < scene.bodies.size(); ++i)
    requireUtf8(scene.bodies[i].name, "body " + std::to_string(i) + " name");
  io::ordered doc = io::sceneToJson(scene);
  if (events && !events->empty()) {
    // Written, then read back against the scene: what the file holds is what a load accepts.
    io::ordered list = io::ordered::array();
    for (const ScriptedEvent& ev : events->events()) list.push_back(io::eventToJson(ev));
    const json as_read = json::parse(list.dump());
    const std::string origin = "events";
    try {
      io::readEvents(Field(as_read, "events", origin), scene);
    } catch (const FileFormatError& e) {
      throw InvalidInputError(std::string("events do not fit the scene: ") + e.what());
    }
    doc["events"] = std::move(list);
  }
  io::pretty(text, doc, 0);
  text += '\n';
}

void writeSceneText(const std::string& text, const std::string& path) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw FileFormatError(path, 0, "cannot open file for writing");
  out << text;
  out.flush();
  if (!out) throw FileFormatError(path, 0, "write failed");
}

}  // namespace

// The events are read and checked too (an error in them is an error in the file), then dropped.
Scene loadSceneFile(const std::string& path) { return loadSceneFileWithEvents(path).scene; }

static SceneFile loadSceneFileWithEventsUnguarded(const std::string& path);

SceneFile loadSceneFileWithEvents(const std::string& path) {
  return reportingOutOfMemory("loadSceneFile", [&] { return loadSceneFileWithEventsUnguarded(path); });
}

static SceneFile loadSceneFileWithEventsUnguarded(const std::string& path) {
  const json doc = io::parseJson(io::readTextFile(path), path);
  SceneFile file;
  file.scene = io::sceneFromJson(doc, path);
  const Field root(doc, "", path);
  if (auto events = root.find("events")) file.events = io::readEvents(*events, file.scene);
  return file;
}

void saveSceneFileWithEvents(const Scene& scene, const EventScript& events, const std::string& path) {
  std::string text;
  saveSceneText(scene, &events, text);
  writeSceneText(text, path);
}

void saveSceneFile(const Scene& scene, const std::string& path) {
  std::string text;
  saveSceneText(scene, nullptr, text);
  writeSceneText(text, path);
}

}  // namespace stabint
