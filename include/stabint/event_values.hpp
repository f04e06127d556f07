#pragma once
/// @file
/// The scripted events as values: what a scene file's "events" hold (docs/scene-format.md) and
/// what EventScript (stabint/events.hpp) plays on a simulator, apart from the player, so that a
/// reader, a writer or a binding of the events needs none of the simulator.
#include <stabint/types.hpp>

#include <Eigen/Core>

#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace stabint {

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

}  // namespace stabint
