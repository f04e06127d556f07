#include "state/checkpoint_slices.hpp"

#include <stabint/errors.hpp>

#include <sstream>
#include <utility>

namespace stabint {
namespace {

// Replaces v[first, first + count) with `with` (a scene's pins may be more or fewer).
template <typename T>
void replaceRange(std::vector<T>& v, int first, int count, const std::vector<T>& with) {
  v.erase(v.begin() + first, v.begin() + first + count);
  v.insert(v.begin() + first, with.begin(), with.end());
}

// Scene rows [first, first + count) of the batch's one user-force ramp `all` take the scene's own
// ramp `own` at time t. The batch keeps one ramp (one t0, t1) for all particles: a scene's ramp
// over a step other than the batch's fits only when one of the two is over by t (its value then
// stays, evaluated as (1 - s) f + s f: round-off, as in setExternalForces).
void spliceForces(Forcing::Ramp& all, int first, int count, const Forcing::Ramp& own, double t, int particles,
                  const std::string& where) {
  if (!own.active) {
    if (all.active) {
      all.start.middleRows(first, count).setZero();
      all.end.middleRows(first, count).setZero();
    }
    return;
  }
  if (!all.active) {
    all =
        Forcing::Ramp{own.t0, own.t1, Eigen::MatrixX3d::Zero(particles, 3), Eigen::MatrixX3d::Zero(particles, 3), true};
  } else if (own.t0 != all.t0 || own.t1 != all.t1) {
    if (!(own.t1 > t)) {
      all.start.middleRows(first, count) = own.end;
      all.end.middleRows(first, count) = own.end;
      return;
    }
    if (all.t1 > t)
      throw InvalidInputError(where + "its external forces ramp over [" + exactText(own.t0) + ", " + exactText(own.t1) +
                              "], the batch's over [" + exactText(all.t0) + ", " + exactText(all.t1) +
                              "]: one ramp for all scenes");
    all.start = all.end;  // the other scenes' ramps are over: their values stay
    all.t0 = own.t0;
    all.t1 = own.t1;
  }
  all.start.middleRows(first, count) = own.start;
  all.end.middleRows(first, count) = own.end;
}

}  // namespace

std::string exactText(double value) {
  std::ostringstream out;
  out.precision(17);
  out << value;
  return out.str();
}

CheckpointData cutScene(const CheckpointData& all, const SceneSlice& slice, std::uint64_t fingerprint,
                        const SceneBook& book, bool active, bool has_user_forces) {
  const SceneSegment& seg = slice.segment;
  CheckpointData d;
  d.scene_fingerprint = fingerprint;
  d.particles = seg.num_particles;
  const std::size_t pb = std::size_t(slice.pin_block);
  d.elements.pins = rangeOf(all.elements.pins, seg.first_element[pb], seg.num_elements[pb]);
  for (Pin& pin : d.elements.pins) pin.vertex -= seg.first_particle;
  static_cast<SceneBook&>(d) = book;
  // An inactive scene's rows of the history slots hold its kept state, not its history.
  d.motion.has_history = all.motion.has_history && active;
  d.motion.x = all.motion.x.middleRows(seg.first_particle, seg.num_particles);
  d.motion.v = all.motion.v.middleRows(seg.first_particle, seg.num_particles);
  d.motion.x_prev = all.motion.x_prev.middleRows(seg.first_particle, seg.num_particles);
  d.motion.v_prev = all.motion.v_prev.middleRows(seg.first_particle, seg.num_particles);
  d.forcing.pins = rangeOf(all.forcing.pins, seg.first_element[pb], seg.num_elements[pb]);
  // The batch's ramp has rows of zeros for the scenes never given forces: those have none, as
  // their own Simulators (for which an active ramp means a pushed scene, no conserved momentum).
  if (has_user_forces) {
    const Forcing::Ramp& r = all.forcing.user_forces;
    d.forcing.user_forces = Forcing::Ramp{r.t0, r.t1, r.start.middleRows(seg.first_particle, seg.num_particles),
                                          r.end.middleRows(seg.first_particle, seg.num_particles), true};
  }
  d.forcing.colliders = rangeOf(all.forcing.colliders, seg.first_collider, seg.num_colliders);
  for (std::size_t b = 0; b < all.elements.stiffness.size(); ++b) {
    d.elements.stiffness.push_back(rangeOf(all.elements.stiffness[b], seg.first_element[b], seg.num_elements[b]));
    d.elements.enabled.push_back(rangeOf(all.elements.enabled[b], seg.first_element[b], seg.num_elements[b]));
  }
  // The scene's entries of the batch's contact log, numbered from its first pair. Every group's
  // end (0) is kept, so that the scenes' logs of one batch line up group by group
  // (mergeContactLogs); an empty group changes nothing when replayed.
  const std::size_t cb = std::size_t(slice.contact_block);
  const int first = seg.first_element[cb], count = seg.num_elements[cb];
  if (count > 0)
    for (std::int32_t entry : all.contact_log) {
      const int e = (entry > 0 ? entry : -entry) - 1;
      if (entry == 0)
        d.contact_log.push_back(0);
      else if (e >= first && e < first + count)
        d.contact_log.push_back(entry > 0 ? e - first + 1 : -(e - first + 1));
    }
  return d;
}

void spliceScene(CheckpointData& all, std::vector<SceneSegment>& segments, int scene, int pin_block,
                 const CheckpointData& d, double time, const std::vector<Collider>& own_colliders,
                 const std::string& where) {
  SceneSegment& seg = segments[std::size_t(scene)];
  const std::size_t pb = std::size_t(pin_block);
  const int first_pin = seg.first_element[pb], pins = seg.num_elements[pb];
  std::vector<Pin> pin_list = d.elements.pins;
  for (Pin& pin : pin_list) pin.vertex += seg.first_particle;
  replaceRange(all.elements.pins, first_pin, pins, pin_list);
  replaceRange(all.forcing.pins, first_pin, pins, d.forcing.pins);
  for (std::size_t b = 0; b < all.elements.stiffness.size(); ++b) {
    replaceRange(all.elements.stiffness[b], seg.first_element[b], seg.num_elements[b], d.elements.stiffness[b]);
    replaceRange(all.elements.enabled[b], seg.first_element[b], seg.num_elements[b], d.elements.enabled[b]);
  }
  // The scene's pin range takes the checkpoint's count: the later scenes' pins move with it.
  const int moved = static_cast<int>(pin_list.size()) - pins;
  seg.num_elements[pb] += moved;
  for (std::size_t s = std::size_t(scene) + 1; s < segments.size(); ++s) segments[s].first_element[pb] += moved;

  const auto rows = [&](Eigen::MatrixX3d& m) { return m.middleRows(seg.first_particle, seg.num_particles); };
  rows(all.motion.x) = d.motion.x;
  rows(all.motion.v) = d.motion.v;
  rows(all.motion.x_prev) = d.motion.x_prev;
  rows(all.motion.v_prev) = d.motion.v_prev;
  for (int c = 0; c < seg.num_colliders; ++c) {
    // A checkpoint without collider motion (version 2) has its colliders on their scene laws.
    const Collider& own = own_colliders[std::size_t(c)];
    all.forcing.colliders[std::size_t(seg.first_collider + c)] =
        d.forcing.colliders.empty() ? Forcing::ColliderMotion{0.0, 0.0, own.center, own.center, own.velocity, false}
                                    : d.forcing.colliders[std::size_t(c)];
  }
  spliceForces(all.forcing.user_forces, seg.first_particle, seg.num_particles, d.forcing.user_forces, time,
               static_cast<int>(all.motion.x.rows()), where);
}

std::vector<std::int32_t> mergeContactLogs(const std::vector<CheckpointData>& scenes,
                                           const std::vector<SceneSegment>& segments, int contact_block) {
  const std::size_t cb = std::size_t(contact_block);
  std::vector<std::vector<std::vector<std::int32_t>>> groups(scenes.size());  // per scene, per group: entries
  std::size_t count = 0;
  bool first = true;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    if (segments[s].num_elements[cb] == 0) continue;
    groups[s].emplace_back();
    for (std::int32_t entry : scenes[s].contact_log) {
      if (entry != 0) {
        const int e = (entry > 0 ? entry : -entry) - 1 + segments[s].first_element[cb];
        groups[s].back().push_back(entry > 0 ? e + 1 : -(e + 1));
      } else {
        groups[s].emplace_back();
      }
    }
    groups[s].pop_back();  // after the last group's end (checked by checkRestorable)
    if (!first && groups[s].size() != count)
      throw InvalidInputError("restore: scene " + std::to_string(s) +
                              ": its contact set changes do not line up with the other scenes' (checkpoints of one "
                              "batch only)");
    count = groups[s].size();
    first = false;
  }
  // A group of the batch's log lists the pairs entering and leaving in one step; the replay takes
  // them apart by sign, so scene after scene gives the batch's change.
  std::vector<std::int32_t> merged;
  for (std::size_t g = 0; g < count; ++g) {
    for (const auto& scene : groups)
      if (!scene.empty()) merged.insert(merged.end(), scene[g].begin(), scene[g].end());
    merged.push_back(0);
  }
  return merged;
}

}  // namespace stabint
