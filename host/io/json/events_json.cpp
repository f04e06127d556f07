// Scripted events in a scene file (include/stabint/events.hpp), read and written:
// {"frame": f, "<kind>": {...}}, one action per event. A new kind of event adds a key here, in
// eventToJson, and a case in EventScript::apply.
#include "io/json/json_internal.hpp"

#include "elements/element_type.hpp"

#include <stabint/errors.hpp>

#include <cstddef>
#include <initializer_list>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace stabint::io {

namespace {

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
  const int count = elementType(e.kind).count(s);
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

}  // namespace

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

namespace {

ordered pathToJson(const std::vector<PathKey>& keys) {
  ordered path = ordered::array();
  for (const PathKey& k : keys)
    path.push_back(
        ordered::array({ordered(k.frame), ordered(k.position.x()), ordered(k.position.y()), ordered(k.position.z())}));
  return path;
}

}  // namespace

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

}  // namespace stabint::io
