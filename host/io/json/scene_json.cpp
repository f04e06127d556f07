// JSON scene files (docs/scene-format.md), the public entry points: load a file (its scene and
// events), save one. Every error names the file and the JSON field path; the reading, writing
// and checks are by concern in the other files of this folder.
#include "io/json/json_internal.hpp"

#include "common/out_of_memory.hpp"
#include "common/text_reader.hpp"

#include <stabint/errors.hpp>
#include <stabint/events.hpp>
#include <stabint/io.hpp>

#include <cstddef>
#include <fstream>
#include <string>
#include <utility>

namespace stabint {

using io::Field;
using io::json;

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
