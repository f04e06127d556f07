// Scripted events (include/stabint/events.hpp, docs/scene-format.md "Events"): the event
// structs, EventScript and the scene files with events.
#include "common.hpp"

#include <utility>

namespace stabint::py {

using namespace nb::literals;

void bindEvents(nb::module_& m) {
  nb::class_<PathKey>(m, "PathKey", "A keyframe of a path: the position at the end of step `frame - 1`.")
      .def(nb::init<>())
      .def(
          "__init__",
          [](PathKey* k, int frame, const Eigen::Vector3d& position) {
            new (k) PathKey{frame, position};
          },
          "frame"_a, "position"_a)
      .def(
          "__init__",
          [](PathKey* k, int frame, const std::array<double, 3>& p) {
            new (k) PathKey{frame, Eigen::Vector3d(p[0], p[1], p[2])};
          },
          "frame"_a, "position"_a, "The same with the position as a sequence of three numbers.")
      .def_rw("frame", &PathKey::frame)
      .def_rw("position", &PathKey::position);
  nb::class_<GrabEvent>(m, "GrabEvent", "Grab particle `vertex` with a handle of `stiffness`, dragged along `path`.")
      .def(nb::init<>())
      .def_rw("id", &GrabEvent::id)
      .def_rw("vertex", &GrabEvent::vertex)
      .def_rw("stiffness", &GrabEvent::stiffness)
      .def_rw("path", &GrabEvent::path);
  nb::class_<ReleaseEvent>(m, "ReleaseEvent", "Release the grab `id`, or (id empty) the last handle on `vertex`.")
      .def(nb::init<>())
      .def_rw("id", &ReleaseEvent::id)
      .def_rw("vertex", &ReleaseEvent::vertex);
  nb::class_<ImpulseEvent>(m, "ImpulseEvent", "Add `velocity` to the velocities of `vertices`.")
      .def(nb::init<>())
      .def_rw("vertices", &ImpulseEvent::vertices)
      .def_rw("velocity", &ImpulseEvent::velocity);
  nb::class_<ElementEvent>(m, "ElementEvent", "Set the stiffness and/or the enabled flag of elements of `kind`.")
      .def(nb::init<>())
      .def_rw("kind", &ElementEvent::kind)
      .def_rw("indices", &ElementEvent::indices)
      .def_rw("stiffness", &ElementEvent::stiffness)
      .def_rw("enabled", &ElementEvent::enabled);
  nb::class_<ColliderEvent>(m, "ColliderEvent",
                            "Move collider `collider` along `path` (Simulator.set_collider_position each frame) or "
                            "with `velocity` (Simulator.set_collider_velocity); exactly one of the two.")
      .def(nb::init<>())
      .def_rw("collider", &ColliderEvent::collider)
      .def_rw("path", &ColliderEvent::path)
      .def_rw("velocity", &ColliderEvent::velocity);
  nb::class_<ScriptedEvent>(m, "ScriptedEvent", "An action applied before step `frame` (0: before the first).")
      .def(nb::init<>())
      .def(
          "__init__",
          [](ScriptedEvent* e, int frame, const EventAction& action) {
            new (e) ScriptedEvent{frame, action};
          },
          "frame"_a, "action"_a)
      .def_rw("frame", &ScriptedEvent::frame)
      .def_rw("action", &ScriptedEvent::action,
              "A GrabEvent, ReleaseEvent, ImpulseEvent, ElementEvent or ColliderEvent (a copy: assign it back).");
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
      .def("apply", &EventScript::apply, "sim"_a,
           "Applies every event not applied yet whose frame is at most sim.step_count, then sets the held "
           "handles' targets and the moving colliders' positions for the end of the coming step.")
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
