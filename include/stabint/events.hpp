#pragma once
/// @file
/// Scripted interaction: timed events that a scene file may carry ("events", docs/scene-format.md)
/// and the player that applies them to a running Simulator before each step, so that a grab, a
/// drag, a release, an impulse, an element change or a collider's motion replays, and can be charted and tested,
/// without a window. Every event goes through the Simulator's per-frame input, so its energy is
/// booked by the same rules (docs/method.md, "Per-frame input"). The events themselves are values
/// (stabint/event_values.hpp).
#include <stabint/event_values.hpp>
#include <stabint/simulator.hpp>

#include <Eigen/Core>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace stabint {

class BatchSimulator;

/// Plays a list of events on a simulator: call apply(sim) before every sim.step() (or
/// apply(batch, scene) before every batch.step(), on one scene of a BatchSimulator). The events
/// must be in non-decreasing frame order, releases must name an earlier grab, grabs' ids must
/// be unique, paths must have increasing frames after their event's and finite positions; the
/// constructor throws InvalidInputError naming the event ("event 3 (frame 60): ...").
///
/// The script has state of its own: which events it applied, the handles it holds (with their
/// pins and paths) and the collider paths under way. A Checkpoint of the simulator does not hold
/// it. EventScript is a value: copy it when taking a checkpoint and play the copy after restoring
/// that checkpoint (a fresh script played on a restored simulator would apply every earlier
/// event again, and lose the handles it holds).
class EventScript {
 public:
  EventScript() = default;
  /// Checks the events (see the class) and takes them; throws InvalidInputError.
  explicit EventScript(std::vector<ScriptedEvent> events);

  /// The events, in the order given.
  const std::vector<ScriptedEvent>& events() const { return events_; }
  /// True when the script has no events.
  bool empty() const { return events_.empty(); }

  /// Applies, in list order, every event not applied yet whose frame is at most
  /// sim.stepCount(), then sets each held handle's target for the end of the coming step from
  /// its path. An event the simulator refuses (a vertex out of its range, say) throws its
  /// InvalidInputError with the event named; the events before it stay applied.
  void apply(Simulator& sim);
  /// Plays the script on scene `scene` of `batch`, as apply(Simulator&) on that scene's own
  /// Simulator: frames are batch.stepCount(scene), vertices, pins, colliders and elements the
  /// scene's own, each event the batch's per-scene input call (refusals name the call and the
  /// scene). An impulse is setState(scene, its positions, the pushed velocities), which the batch
  /// refuses for BDF2 (where Simulator's setVelocities restarts BDF2 with a BE step). One script
  /// object plays on one target: it keeps the handles and paths it started there.
  void apply(BatchSimulator& batch, int scene);

  /// Pin index of a held handle by grab id (-1 when not held).
  int handlePin(const std::string& id) const;

 private:
  /// A path being played: a held handle (the pin of its grab) or a moving collider.
  struct Handle {
    std::size_t event;  ///< index of its grab or collider event in events_
    int pin = -1;       ///< the handle's pin, or the collider's index
    int start_frame = 0;
    Eigen::Vector3d start = Eigen::Vector3d::Zero();
  };
  // The one player of both apply()s, over a Simulator or one scene of a batch (the library's
  // scripting/event_script.cpp).
  template <typename Target>
  void play(Target& target);

  std::vector<ScriptedEvent> events_;
  std::size_t next_ = 0;
  std::vector<Handle> held_;
  std::vector<Handle> collider_paths_;
};

/// A scene file's scene and its events (an empty list when it has none).
struct SceneFile {
  Scene scene;         ///< the scene, validated
  EventScript events;  ///< its events, ready to play
};

/// Loads a scene file with its "events" (docs/scene-format.md); errors as loadSceneFile, with
/// the JSON path of the event ("events[2].grab.path[1]: ...").
SceneFile loadSceneFileWithEvents(const std::string& path);
/// Writes a scene file with events; loadSceneFileWithEvents reads back the same scene and
/// events exactly.
void saveSceneFileWithEvents(const Scene& scene, const EventScript& events, const std::string& path);

}  // namespace stabint
