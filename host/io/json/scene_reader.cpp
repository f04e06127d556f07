// Reading a scene file: the parts it assembles (particles, masses,
// selections, springs, tets, generic elements, pins, force fields, bodies, colliders), and
// sceneFromJson that puts them together and validates the scene.
#include "io/json/json_internal.hpp"

#include "elements/element_type.hpp"
#include "io/mesh_scene.hpp"
#include "common/text_reader.hpp"
#include "scene/lumping.hpp"
#include "scene/scene_batch.hpp"
#include "common/validation.hpp"

#include <stabint/errors.hpp>
#include <stabint/io.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <iterator>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace stabint::io {

namespace {

namespace fs = std::filesystem;

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

}  // namespace

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

namespace {

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

}  // namespace

// JSON key of a type with a generic form: its identifier, plural ("triangle_strains").
std::string genericKey(const ElementType& type) { return std::string(type.identifier()) + "s"; }

std::vector<const ElementType*> genericTypes() {
  std::vector<const ElementType*> out;
  for (const ElementType* type : elementTypes()) {
    if (!type->jsonFields().empty()) out.push_back(type);
  }
  return out;
}

namespace {

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

// Colliders (docs/scene-format.md): {"shape": "plane" | "sphere" | "box" | "capsule" | "mesh",
// "center", the shape's own fields (normal; radius; half_extents; end, radius; a mesh's "mesh" file
// entry, as the scene's, or its "vertices" and "triangles"), and optionally velocity, friction,
// stiffness, elastic_ratio, restitution and the particles it acts on (first_particle,
// num_particles)}; the values are checked by validateScene.

// A mesh collider's surface from a mesh file entry (paths relative to `dir`): an OBJ's triangles,
// or a tet mesh's boundary faces.
void readColliderMesh(const Field& entry, const fs::path& dir, Collider& c) {
  Scene m = meshFromField(entry, dir);
  if (auto t = entry.find("translate")) translate(m, t->vector3());
  c.mesh_vertices = m.positions;
  c.mesh_triangles = m.triangles.empty() ? tetSurface(m.tets) : m.triangles;
}

void readColliders(const Field& list, const fs::path& dir, Scene& s) {
  for (size_t i = 0; i < list.size(); ++i) {
    const Field e = list[i];
    e.allowOnly({"shape", "center", "normal", "radius", "half_extents", "end", "mesh", "vertices", "triangles",
                 "velocity", "friction", "stiffness", "elastic_ratio", "restitution", "first_particle",
                 "num_particles"});
    Collider c;
    const Field shape = e.member("shape");
    const std::string name = shape.string();
    const std::optional<ColliderShape> found = valueNamed(name, colliderShapeName, kColliderShapeCount);
    if (!found)
      shape.fail("unknown collider shape \"" + shown(name) + "\" (" +
                 enumNames(colliderShapeName, kColliderShapeCount) + ")");
    c.shape = *found;
    c.center = vectorOr(e, "center");
    if (auto f = e.find("normal")) c.normal = f->vector3();
    if (auto f = e.find("radius")) c.radius = f->number();
    if (auto f = e.find("half_extents")) c.half_extents = f->vector3();
    if (auto f = e.find("end")) c.end = f->vector3();
    if (auto f = e.find("mesh")) readColliderMesh(*f, dir, c);
    if (auto f = e.find("vertices")) c.mesh_vertices = readRows(*f);
    if (auto f = e.find("triangles")) c.mesh_triangles = readTriangles(*f, static_cast<int>(c.mesh_vertices.rows()));
    c.velocity = vectorOr(e, "velocity");
    if (auto f = e.find("friction")) c.friction = f->number();
    if (auto f = e.find("stiffness")) c.stiffness = f->number();
    if (auto f = e.find("elastic_ratio")) c.elastic_ratio = f->number();
    if (auto f = e.find("restitution")) c.restitution = f->number();
    if (auto f = e.find("first_particle")) c.first_particle = f->integer();
    if (auto f = e.find("num_particles")) c.num_particles = f->integer();
    s.colliders.push_back(c);
  }
}

}  // namespace

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
  if (auto f = root.find("colliders")) readColliders(*f, dir, s);

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

}  // namespace stabint::io
