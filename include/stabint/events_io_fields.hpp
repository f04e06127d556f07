#pragma once
/// @file
/// The field lists of the structs of stabint/event_values.hpp (the events) and stabint/io.hpp (the
/// materials), `FIELD(name, "doc")` in each struct's order, and their FieldTables
/// (stabint/field_list.hpp), from which Python's classes are generated. They are kept here, not
/// next to their structs as the scene's and the reports' are, so that those two headers stay as
/// they are while others change them; a field added to one of these structs is one line here.
#include <stabint/event_values.hpp>
#include <stabint/field_list.hpp>
#include <stabint/io.hpp>

namespace stabint {

/// The fields of PathKey, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_PATH_KEY_FIELDS(FIELD)                  \
  FIELD(frame, "the step count at which it is reached") \
  FIELD(position, "m, the target there")
/// @cond
STABINT_FIELD_TABLE_(PathKey, STABINT_PATH_KEY_FIELDS,
                     "A keyframe of a path: the position at the end of step `frame - 1`.")
/// @endcond

/// The fields of GrabEvent, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_GRAB_EVENT_FIELDS(FIELD)                              \
  FIELD(id, "for the release; may be empty (release by vertex then)") \
  FIELD(vertex, "the grabbed particle")                               \
  FIELD(stiffness, "N/m, the handle's pin")                           \
  FIELD(path, "keyframes of the drag; empty: the handle stays put")
/// @cond
STABINT_FIELD_TABLE_(GrabEvent, STABINT_GRAB_EVENT_FIELDS,
                     "Grab particle `vertex` with a handle of `stiffness`, dragged along `path`.")
/// @endcond

/// The fields of ReleaseEvent, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_RELEASE_EVENT_FIELDS(FIELD)              \
  FIELD(id, "the grab's id; empty: release by `vertex`") \
  FIELD(vertex, "the particle whose most recent handle is released (when `id` is empty)")
/// @cond
STABINT_FIELD_TABLE_(ReleaseEvent, STABINT_RELEASE_EVENT_FIELDS,
                     "Release the grab `id`, or (id empty) the last handle on `vertex`.")
/// @endcond

/// The fields of ImpulseEvent, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_IMPULSE_EVENT_FIELDS(FIELD) \
  FIELD(vertices, "the particles pushed")   \
  FIELD(velocity, "m/s, added to each one's velocity")
/// @cond
STABINT_FIELD_TABLE_(ImpulseEvent, STABINT_IMPULSE_EVENT_FIELDS, "Add `velocity` to the velocities of `vertices`.")
/// @endcond

/// The fields of ElementEvent, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_ELEMENT_EVENT_FIELDS(FIELD)     \
  FIELD(kind, "which element list")             \
  FIELD(indices, "indices into that list")      \
  FIELD(stiffness, "the new stiffness, if any") \
  FIELD(enabled, "the new enabled flag, if any")
/// @cond
STABINT_FIELD_TABLE_(ElementEvent, STABINT_ELEMENT_EVENT_FIELDS,
                     "Set the stiffness and/or the enabled flag of elements of `kind`.")
/// @endcond

/// The fields of ColliderEvent, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_COLLIDER_EVENT_FIELDS(FIELD)             \
  FIELD(collider, "index in Scene.colliders")            \
  FIELD(path, "keyframes of Collider.center (or empty)") \
  FIELD(velocity, "m/s, the collider's new velocity (or None)")
/// @cond
STABINT_FIELD_TABLE_(ColliderEvent, STABINT_COLLIDER_EVENT_FIELDS,
                     "Move collider `collider` along `path` (Simulator.set_collider_position each frame) or with "
                     "`velocity` (Simulator.set_collider_velocity); exactly one of the two.")
/// @endcond

/// The fields of ScriptedEvent, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_SCRIPTED_EVENT_FIELDS(FIELD)            \
  FIELD(frame, "applied before the step of this index") \
  FIELD(action, "a GrabEvent, ReleaseEvent, ImpulseEvent, ElementEvent or ColliderEvent (a copy: assign it back)")
/// @cond
STABINT_FIELD_TABLE_(ScriptedEvent, STABINT_SCRIPTED_EVENT_FIELDS,
                     "An action applied before step `frame` (0: before the first).")
/// @endcond

/// The fields of ClothMaterial, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_CLOTH_MATERIAL_FIELDS(FIELD)                             \
  FIELD(areal_density, "kg/m^2")                                         \
  FIELD(stretch_stiffness, "springs along edges (model Springs)")        \
  FIELD(bend_stiffness, "springs across interior edges (model Springs)") \
  FIELD(model, "springs, or triangle strain and bending hinges")         \
  FIELD(strain_stiffness, "triangle strain k, N/m (model Triangles)")    \
  FIELD(strain_min, "triangle strain limits (model Triangles)")          \
  FIELD(strain_max, "triangle strain limits (model Triangles)")          \
  FIELD(hinge_stiffness, "bending hinge k, J (model Triangles)")
/// @cond
STABINT_FIELD_TABLE_(ClothMaterial, STABINT_CLOTH_MATERIAL_FIELDS, "Material of a loaded cloth mesh.")
/// @endcond

/// The fields of SolidMaterial, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_SOLID_MATERIAL_FIELDS(FIELD) \
  FIELD(density, "kg/m^3")                   \
  FIELD(stiffness, "tet strain stiffness (Pa)")
/// @cond
STABINT_FIELD_TABLE_(SolidMaterial, STABINT_SOLID_MATERIAL_FIELDS, "Material of a loaded tet mesh.")
/// @endcond

}  // namespace stabint
