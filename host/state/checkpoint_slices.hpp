#pragma once
// A batch's checkpoint cut into its scenes' and put back together (docs/batch_design.md,
// "Checkpoints"): the batch's state is what a Simulator of the concatenation saves, and a scene's
// checkpoint is its part of that state, numbered as the scene alone numbers it, in Simulator's
// format. These are functions of the values alone; the driver gathers and applies the state
// (host/driver/batch_checkpoint.cpp).
#include "scene/scene_batch.hpp"
#include "state/checkpoint.hpp"

#include <stabint/scene.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace stabint {

/// `count` entries of `v` from `first`.
template <typename T>
std::vector<T> rangeOf(const std::vector<T>& v, int first, int count) {
  return std::vector<T>(v.begin() + first, v.begin() + first + count);
}

/// A double to the bit (17 significant digits), as messages and a batch checkpoint's options
/// write it.
std::string exactText(double value);

/// Where one scene lies in its batch: its segment of the concatenation, and the blocks of the pins
/// and of the contact pairs in the batch's SceneData.
struct SceneSlice {
  SceneSegment segment;
  int pin_block = 0;
  int contact_block = 0;
};

/// Scene's part of the batch's state `all`, as a Simulator of the scene alone saves it: its rows,
/// pins (their vertices its own), elements, collider motion, and its entries of the contact log
/// numbered from its first pair (every group's end kept, so that the scenes' logs of one batch
/// line up group by group: mergeContactLogs); its book is `book`, and it has the batch's BDF2
/// history only when `active` (an inactive scene's history rows hold its kept state) and the
/// user-force ramp's rows only when `has_user_forces` (a ramp means a pushed scene).
CheckpointData cutScene(const CheckpointData& all, const SceneSlice& slice, std::uint64_t fingerprint,
                        const SceneBook& book, bool active, bool has_user_forces);

/// Writes scene `scene`'s checkpoint `d` into the batch's state `all` and its `segments` (its
/// pins may be more or fewer than the scene has now: the later scenes' pin ranges move) as of
/// the batch's time `time`. A checkpoint without collider motion (version 2) puts the scene's
/// colliders (`own_colliders`) on their scene laws. InvalidInputError, prefixed `where`, for a
/// user-force ramp the batch's one ramp cannot hold.
void spliceScene(CheckpointData& all, std::vector<SceneSegment>& segments, int scene, int pin_block,
                 const CheckpointData& d, double time, const std::vector<Collider>& own_colliders,
                 const std::string& where);

/// The scenes' contact logs (each numbered from its first pair, all with the groups of one
/// batch's log) as the batch's; InvalidInputError where their groups do not line up.
std::vector<std::int32_t> mergeContactLogs(const std::vector<CheckpointData>& scenes,
                                           const std::vector<SceneSegment>& segments, int contact_block);

}  // namespace stabint
