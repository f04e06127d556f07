// Writing a scene: its explicit form (what saveSceneFile writes and loadSceneFile reads back
// bit for bit), laid out one item per line where a container does not fit on one.
#include "io/json/json_internal.hpp"

#include "elements/element_type.hpp"

#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

namespace stabint::io {

ordered vec(const Eigen::Vector3d& v) { return ordered::array({v.x(), v.y(), v.z()}); }

namespace {

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

}  // namespace

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

namespace {

// A pin, its target's motion only where it has one.
ordered pinJson(const Pin& p) {
  ordered target = {{"position", vec(p.target.position)}};
  if (!plainZero(p.target.velocity) || !plainZero(p.target.amplitude) || !plainZero(p.target.frequency)) {
    target["velocity"] = vec(p.target.velocity);
    target["amplitude"] = vec(p.target.amplitude);
    target["frequency"] = p.target.frequency;
  }
  return {{"vertex", p.vertex}, {"stiffness", p.stiffness}, {"target", std::move(target)}};
}

ordered forceFieldJson(const ForceField& f) {
  ordered e;
  if (!f.particles.empty()) e["particles"] = f.particles;
  e["force"] = vec(f.force);
  e["rate"] = vec(f.rate);
  e["amplitude"] = vec(f.amplitude);
  e["frequency"] = f.frequency;
  return e;
}

// A collider with the fields of its shape.
ordered colliderJson(const Collider& c) {
  ordered e;
  e["shape"] = colliderShapeName(c.shape);  // validated by saveSceneFile
  e["center"] = vec(c.center);
  if (c.shape == ColliderShape::Plane) e["normal"] = vec(c.normal);
  if (c.shape == ColliderShape::Box) e["half_extents"] = vec(c.half_extents);
  if (c.shape == ColliderShape::Capsule) e["end"] = vec(c.end);
  if (c.shape == ColliderShape::Sphere || c.shape == ColliderShape::Capsule) e["radius"] = c.radius;
  if (c.shape == ColliderShape::Mesh) {
    e["vertices"] = rows(c.mesh_vertices);
    ordered triangles = ordered::array();
    for (const auto& t : c.mesh_triangles) triangles.push_back(ordered::array({t[0], t[1], t[2]}));
    e["triangles"] = std::move(triangles);
  }
  if (c.moving()) e["velocity"] = vec(c.velocity);
  e["friction"] = c.friction;
  e["stiffness"] = c.stiffness;
  e["elastic_ratio"] = c.elastic_ratio;
  e["restitution"] = c.restitution;
  if (c.num_particles != -1) {  // -1: every particle, the default
    e["first_particle"] = c.first_particle;
    e["num_particles"] = c.num_particles;
  }
  return e;
}

}  // namespace

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
    for (const Pin& p : s.pins) a.push_back(pinJson(p));
    doc["pins"] = std::move(a);
  }
  if (!s.force_fields.empty()) {
    ordered a = ordered::array();
    for (const ForceField& f : s.force_fields) a.push_back(forceFieldJson(f));
    doc["force_fields"] = std::move(a);
  }
  if (!s.colliders.empty()) {
    ordered a = ordered::array();
    for (const Collider& c : s.colliders) a.push_back(colliderJson(c));
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

}  // namespace stabint::io
