#pragma once
// Many scenes as one (docs/batch_design.md): the scenes' particles one after another and, type by
// type, their element lists one after another with shifted vertex indices. No element couples two
// scenes, so the global matrix of the concatenation is block-diagonal and its local step and
// gather give each scene the sums its own simulator forms, in the same order; what sums over
// particles or elements (energies, the blend's decisions) needs the segments to stay per scene.
#include <stabint/scene.hpp>

#include <vector>

namespace stabint {

/// Appends `part` after the particles of `into`: positions, masses, every element type's list
/// (ElementType::appendShifted), force fields ("all particles" becomes the part's own), bodies
/// and triangles, with particle indices shifted, and colliders, which act on the part's particles
/// only (Collider::first_particle, num_particles). Gravity stays `into`'s. The scene files'
/// "parts" and concatenateScenes both build with it.
void appendScene(Scene& into, const Scene& part);

/// Where one scene lies in a concatenation.
struct SceneSegment {
  int first_particle = 0;
  int num_particles = 0;
  /// Per element type, in elementTypes() order: the scene's elements are
  /// [first_element[i], first_element[i] + num_elements[i]) of that type's list (and of its
  /// SceneData block, which keeps the list's order).
  std::vector<int> first_element;
  std::vector<int> num_elements;
  /// The scene's colliders are [first_collider, first_collider + num_colliders) of the
  /// concatenation's, acting on the scene's particles only.
  int first_collider = 0;
  int num_colliders = 0;
  /// With self-contact, the collider whose contact pairs hold the scene's particles on their
  /// side of the surfaces they rest on within the solve, and where self-contact pushed them while
  /// the elements relax after the solve (docs/method.md, "Self-contact"): the concatenation's,
  /// right after the scene's own colliders, and no collider of the scene's (-1: none).
  int support_collider = -1;
};

struct SceneBatch {
  Scene scene;                         // the concatenation
  std::vector<SceneSegment> segments;  // one per scene, in order
};

/// Validates every scene (InvalidInputError "scene <i>: ...") and concatenates them. The batch
/// needs one gravity (Scene has one): a scene whose gravity differs is refused, naming it, until
/// the batch has per-segment gravity (docs/batch_design.md, "Segments"). Each scene's colliders
/// act on its own particles only.
SceneBatch concatenateScenes(const std::vector<Scene>& scenes);

/// `scenes` concatenated (or, with `one`, the single scene as batchOfOne gives it) with a support
/// collider after the own colliders of each scene whose flag in `supported` is set
/// (SceneSegment::support_collider; -1 for the others): a plane far below everything, which the
/// broad phase never enters and whose pairs act with the half-spaces self-contact writes.
SceneBatch withSupportColliders(const std::vector<Scene>& scenes, const std::vector<char>& supported, bool one);

/// `scene` itself as a batch of one (a Simulator's: its scene as it is, not appended to an empty
/// one), with the segment that covers all of it. Not validated: SceneData validates it.
SceneBatch batchOfOne(const Scene& scene);

}  // namespace stabint
