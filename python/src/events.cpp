// Scripted events (include/stabint/events.hpp, docs/scene-format.md "Events"): the event
// structs, EventScript and the scene files with events.
#include "fields.hpp"

#include <array>
#include <utility>

namespace stabint::py {

using namespace nb::literals;

// A keyframe's position may also be a sequence of three numbers (see bindExtras).
template <>
void bindExtras(nb::class_<PathKey>& c) {
  c.def(
      "__init__",
      [](PathKey* k, int frame, const std::array<double, 3>& p) {
        new (k) PathKey{frame, Eigen::Vector3d(p[0], p[1], p[2])};
      },
      "frame"_a, "position"_a, "The same with the position as a sequence of three numbers.");
}

void bindEvents(nb::module_& m) {
  // The events from their tables (stabint/events_io_fields.hpp); ScriptedEvent's action brings
  // every kind of event, and GrabEvent's path PathKey.
  bindStruct<ScriptedEvent>(m);
  nb::class_<EventScript>(m, "EventScript",
                          "Plays timed events on a simulator: call apply(sim) before every sim.step(). Its progress "
                          "(events applied, handles held, collider paths under way) is not part of a Checkpoint: "
                          "copy the script (copy.copy) with the checkpoint and play the copy after restoring it.")
      .def(nb::init<>())
      .def(nb::init<std::vector<ScriptedEvent>>(), "events"_a,
           "Raises InvalidInputError naming the event for frames out of order, a release of no held grab, "
           "bad paths or values.")
      .def_prop_ro("events", &EventScript::events, "The events (a copy).")
      .def("empty", &EventScript::empty)
      .def("__len__", [](const EventScript& e) { return e.events().size(); })
      .def("apply", nb::overload_cast<Simulator&>(&EventScript::apply), "sim"_a,
           "Applies every event not applied yet whose frame is at most sim.step_count, then sets the held "
           "handles' targets and the moving colliders' positions for the end of the coming step.")
      .def("apply", nb::overload_cast<BatchSimulator&, int>(&EventScript::apply), "batch"_a, "scene"_a,
           "The same on one scene of a batch (call it before every batch.step()): frames are "
           "batch.step_count(scene), indices the scene's own; an impulse is the scene's set_state, refused for BDF2.")
      .def("handle_pin", &EventScript::handlePin, "id"_a, "Pin index of the held handle of grab `id` (-1: none).")
      .def("__copy__", [](const EventScript& e) { return EventScript(e); })
      .def(
          "__deepcopy__", [](const EventScript& e, nb::handle) { return EventScript(e); }, "memo"_a);
  m.def(
      "load_scene_file_with_events",
      [](const std::string& path) {
        SceneFile file = loadSceneFileWithEvents(path);
        return std::make_pair(std::move(file.scene), std::move(file.events));
      },
      "path"_a, "A JSON scene file and its \"events\" as (Scene, EventScript); errors name the event's JSON path.");
  m.def("save_scene_file_with_events", &saveSceneFileWithEvents, "scene"_a, "events"_a, "path"_a,
        "Writes a scene file with events that load_scene_file_with_events reads back exactly.");
}

}  // namespace stabint::py
