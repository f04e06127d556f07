#pragma once
/// @file
/// Scripted interaction: timed events that a scene file may carry ("events", docs/scene-format.md)
/// and the player that applies them to a running Simulator before each step, so that a grab, a
/// drag, a release, an impulse, an element change or a collider's motion replays, and can be charted and tested,
/// without a window. Every event goes through the Simulator's per-frame input, so its energy is
/// booked by the same rules (docs/method.md, "Per-frame input").
#include <stabint/simulator.hpp>

#include <Eigen/Core>

#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace stabint {

class BatchSimulator;

/// A keyframe of a dragged handle: its target at the end of step `frame - 1` (i.e. when the
/// simulator's step count is `frame`).
struct PathKey {
  int frame = 0;                                       ///< the step count at which it is reached
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< m, the target there
};

/// Grab particle `vertex` with a handle of `stiffness` (Simulator::grab). The handle starts at
/// the particle's position; with a path it then moves linearly from there to the keyframes in
/// turn (their frames strictly increasing, after the grab's) and stays at the last one.
struct GrabEvent {
  std::string id;             ///< for the release; may be empty (release by vertex then)
  int vertex = 0;             ///< the grabbed particle
  double stiffness = 0.0;     ///< N/m, the handle's pin
  std::vector<PathKey> path;  ///< keyframes of the drag; empty: the handle stays put
};

/// Release a handle (Simulator::release): the grab with this `id`, or when `id` is empty the
/// most recent held handle on `vertex`.
struct ReleaseEvent {
  std::string id;   ///< the grab's id; empty: release by `vertex`
  int vertex = -1;  ///< the particle whose most recent handle is released (when `id` is empty)
};

/// Add `velocity` to the velocities of `vertices` (Simulator::setVelocities): the kinetic
/// energy jump is booked as an event.
struct ImpulseEvent {
  std::vector<int> vertices;                           ///< the particles pushed
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< m/s, added to each one's velocity
};

/// Change elements of one kind (Simulator::setElementStiffness, setElementEnabled): a new
/// stiffness, an enabled flag, or both (the stiffness first).
struct ElementEvent {
  ElementKind kind = ElementKind::Spring;  ///< which element list
  std::vector<int> indices;                ///< indices into that list
  std::optional<double> stiffness;         ///< the new stiffness, if any
  std::optional<bool> enabled;             ///< the new enabled flag, if any
};

/// Move collider `collider` (its index in the scene's list) either along `path`, keyframes of
/// where its reference point (Collider::center) is to be (Simulator::setColliderPosition): from
/// where it is at the event's frame linearly to the keyframes in turn (frames strictly
/// increasing, after the event's), then it stays at the last one; or with `velocity` from the
/// event's frame on (Simulator::setColliderVelocity). Exactly one of the two. A later collider
/// event for the same collider takes over from where the collider then is.
struct ColliderEvent {
  int collider = 0;                         ///< index in Scene::colliders
  std::vector<PathKey> path;                ///< keyframes of Collider::center (or empty)
  std::optional<Eigen::Vector3d> velocity;  ///< m/s, the collider's new velocity (or none)
};

/// What an event does. Extension point: a new kind of event is a new struct here, a case in
/// EventScript's checks and apply, and a key in the scene file's reader and writer
/// (docs/scene-format.md, "Events").
using EventAction = std::variant<GrabEvent, ReleaseEvent, ImpulseEvent, ElementEvent, ColliderEvent>;

/// An action applied before the step whose index is `frame` (0: before the first step).
struct ScriptedEvent {
  int frame = 0;       ///< applied before the step of this index
  EventAction action;  ///< what it does
};

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
