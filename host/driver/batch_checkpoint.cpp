// Checkpoints of a batch (include/stabint/batch.hpp, docs/batch_design.md "Checkpoints"): the
// batch's state is what a Simulator of the concatenation would save, so Simulator's CheckpointData,
// ElementChanges::save/restore and ContactResolver::restore serve it unchanged; a scene's
// checkpoint is its part of that state, numbered as the scene alone numbers it, in Simulator's
// format. A scene's restore splices its checkpoint into the batch's state and applies the whole.
#include "driver/batch_simulator.hpp"

#include "elements/element_type.hpp"
#include "integrator/integrator_steps.hpp"
#include "common/out_of_memory.hpp"
#include "common/validation.hpp"

#include <stabint/errors.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace stabint {
namespace {

// Replaces v[first, first + count) with `with` (a scene's pins may be more or fewer).
template <typename T>
void replaceRange(std::vector<T>& v, int first, int count, const std::vector<T>& with) {
  v.erase(v.begin() + first, v.begin() + first + count);
  v.insert(v.begin() + first, with.begin(), with.end());
}

template <typename T>
std::vector<T> rangeOf(const std::vector<T>& v, int first, int count) {
  return std::vector<T>(v.begin() + first, v.begin() + first + count);
}

std::string timeText(double t) {
  std::ostringstream out;
  out.precision(17);
  out << t;
  return out.str();
}

int pinBlock(const SceneData& data) { return data.blockIndex(pinElementType()); }

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
      throw InvalidInputError(where + "its external forces ramp over [" + timeText(own.t0) + ", " + timeText(own.t1) +
                              "], the batch's over [" + timeText(all.t0) + ", " + timeText(all.t1) +
                              "]: one ramp for all scenes");
    all.start = all.end;  // the other scenes' ramps are over: their values stay
    all.t0 = own.t0;
    all.t1 = own.t1;
  }
  all.start.middleRows(first, count) = own.start;
  all.end.middleRows(first, count) = own.end;
}

// An option's value as a batch checkpoint records it: a double to the bit (17 digits), an int
// in decimal, an enum by its name.
std::string optionText(double value) { return timeText(value); }
std::string optionText(int value) { return std::to_string(value); }
std::string optionText(Integrator value) { return integratorName(value); }
std::string optionText(Acceleration value) { return accelerationName(value); }
std::string optionText(GlobalSolve value) { return globalSolveName(value); }
std::string optionText(BackendKind value) { return backendName(value); }

// The options a batch checkpoint records and a restore compares (include/stabint/batch.hpp):
// every row of the options table (stabint/options_table.h) but `iterations`, which setIterations
// changes at run time, and where the work runs (`backend` and the nested `opencl`): the state means
// the same on every device, as a Simulator's checkpoint does.
std::vector<std::pair<std::string, std::string>> recordedOptions(const SimulatorOptions& o) {
  std::vector<std::pair<std::string, std::string>> out;
#define STABINT_RECORD_OPTION(type, name, default_value, rule, doc)          \
  if (std::string(#name) != "iterations" && std::string(#name) != "backend") \
    out.emplace_back(#name, optionText(o.name));
#define STABINT_RECORD_NESTED(type, name, fields, doc)
  STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_RECORD_OPTION, STABINT_RECORD_NESTED)
#undef STABINT_RECORD_OPTION
#undef STABINT_RECORD_NESTED
  return out;
}

// InvalidInputError naming the first option of `options` whose value differs from the one the
// checkpoint recorded (or that it did not record).
void checkSameOptions(const std::vector<std::pair<std::string, std::string>>& recorded,
                      const SimulatorOptions& options) {
  for (const auto& option : recordedOptions(options)) {
    // Named copies: a lambda may not capture a structured binding in C++17 (clang refuses it).
    const std::string& name = option.first;
    const std::string& value = option.second;
    const auto found = std::find_if(recorded.begin(), recorded.end(), [&](const auto& r) { return r.first == name; });
    if (found == recorded.end())
      throw InvalidInputError("restore: the batch checkpoint does not record the option " + name +
                              " (a batch checkpoint restores into a batch of the same options)");
    if (found->second != value)
      throw InvalidInputError("restore: the batch checkpoint was taken with " + name + " = " + found->second +
                              ", this batch has " + name + " = " + value +
                              ": a batch checkpoint restores into a batch of the same options");
  }
}

}  // namespace

CheckpointData BatchDriver::batchData() {
  settleEvents();
  CheckpointData d;
  d.scene_fingerprint = sceneFingerprint(data_.scene());
  d.particles = data_.numParticles();
  d.time = t_;
  d.motion.has_history = has_history_;
  d.motion.x = x_;
  d.motion.v = v_;
  backend_->read(kXPrev, d.motion.x_prev);
  backend_->read(kVPrev, d.motion.v_prev);
  d.forcing = forcing_.state();
  d.elements = data_.elementState();
  d.contact_log = contact_.log();
  return d;
}

CheckpointData BatchDriver::sceneData(const CheckpointData& all, int scene) const {
  const SceneSegment& seg = segments_[std::size_t(scene)];
  const PerScene& p = per_scene_[std::size_t(scene)];
  CheckpointData d;
  d.scene_fingerprint = sceneFingerprint(scenes_[std::size_t(scene)]);
  d.particles = seg.num_particles;
  const std::size_t pb = std::size_t(pinBlock(data_));
  d.elements.pins = rangeOf(all.elements.pins, seg.first_element[pb], seg.num_elements[pb]);
  for (Pin& pin : d.elements.pins) pin.vertex -= seg.first_particle;
  static_cast<SceneBook&>(d) = p;
  // An inactive scene's rows of the history slots hold its kept state, not its history.
  d.motion.has_history = all.motion.has_history && p.active;
  d.motion.x = all.motion.x.middleRows(seg.first_particle, seg.num_particles);
  d.motion.v = all.motion.v.middleRows(seg.first_particle, seg.num_particles);
  d.motion.x_prev = all.motion.x_prev.middleRows(seg.first_particle, seg.num_particles);
  d.motion.v_prev = all.motion.v_prev.middleRows(seg.first_particle, seg.num_particles);
  d.forcing.pins = rangeOf(all.forcing.pins, seg.first_element[pb], seg.num_elements[pb]);
  // The batch's ramp has rows of zeros for the scenes never given forces: those have none, as
  // their own Simulators (for which an active ramp means a pushed scene, no conserved momentum).
  if (p.has_user_forces) {
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
  const std::size_t cb = std::size_t(contact_.block());
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

RestoreTarget BatchDriver::restoreTarget(int scene, const char* call) const {
  checkScene(scene, call);
  const SceneSegment& seg = segments_[std::size_t(scene)];
  RestoreTarget target;
  target.fingerprint = sceneFingerprint(scenes_[std::size_t(scene)]);
  target.particles = seg.num_particles;
  target.element_counts = seg.num_elements;
  target.pin_block = pinBlock(data_);
  target.contact_block = contact_.block();
  target.colliders = std::size_t(seg.num_colliders);
  // A Simulator's messages name the call, not a scene.
  target.where = std::string(call) + ": " + (as_simulator_ ? std::string() : "scene " + std::to_string(scene) + ": ");
  return target;
}

void BatchDriver::splice(CheckpointData& all, std::vector<SceneSegment>& segments, int scene, const CheckpointData& d,
                         double time) const {
  SceneSegment& seg = segments[std::size_t(scene)];
  const std::size_t pb = std::size_t(pinBlock(data_));
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
  const std::vector<Collider>& colliders = scenes_[std::size_t(scene)].colliders;
  for (int c = 0; c < seg.num_colliders; ++c) {
    // A checkpoint without collider motion (version 2) has its colliders on their scene laws.
    const Collider& own = colliders[std::size_t(c)];
    all.forcing.colliders[std::size_t(seg.first_collider + c)] =
        d.forcing.colliders.empty() ? Forcing::ColliderMotion{0.0, 0.0, own.center, own.center, own.velocity, false}
                                    : d.forcing.colliders[std::size_t(c)];
  }
  spliceForces(all.forcing.user_forces, seg.first_particle, seg.num_particles, d.forcing.user_forces, time,
               data_.numParticles(), restoreTarget(scene, "restore").where);
}

std::vector<std::int32_t> BatchDriver::mergeContactLogs(const std::vector<CheckpointData>& scenes) const {
  const std::size_t cb = std::size_t(contact_.block());
  std::vector<std::vector<std::vector<std::int32_t>>> groups(scenes.size());  // per scene, per group: entries
  std::size_t count = 0;
  bool first = true;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    if (segments_[s].num_elements[cb] == 0) continue;
    groups[s].emplace_back();
    for (std::int32_t entry : scenes[s].contact_log) {
      if (entry != 0) {
        const int e = (entry > 0 ? entry : -entry) - 1 + segments_[s].first_element[cb];
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

void BatchDriver::apply(const CheckpointData& all, const std::vector<SceneSegment>& segments,
                        const std::vector<PerScene>& per_scene, bool assemble) {
  ElementChanges elements(data_, forcing_, system_, *backend_);
  if (assemble) {
    const std::vector<std::uint8_t> base = contact_.baseFlags(all.elements.enabled, all.contact_log);
    elements.restore(all.elements, contact_.block(), &base);
    contact_.restore(all.contact_log);
  } else {
    elements.restore(all.elements, contact_.block(), nullptr);
  }
  segments_ = segments;
  backend_->setSegments(segments_);
  const MotionState& motion = all.motion;
  backend_->write(kX, motion.x);
  backend_->write(kV, motion.v);
  backend_->write(kXPrev, motion.x_prev);
  backend_->write(kVPrev, motion.v_prev);
  x_ = motion.x;
  v_ = motion.v;
  v_slot_ = motion.v;
  host_copies_stored_ = false;
  t_ = all.time;
  has_history_ = motion.has_history;
  forcing_.setState(all.forcing);
  per_scene_ = per_scene;
  for (int s = 0; s < size(); ++s) pinsChanged(s);
  // The pairs' geometry is the state's (refreshed after every step), not a checkpoint's field.
  if (contact_.count() > 0) {
    std::vector<ContactPart> parts;
    for (std::size_t s = 0; s < segments_.size(); ++s)
      if (segments_[s].num_colliders > 0) parts.push_back(contactPart(s, 0));
    contact_.refreshHalfSpaces(t_, x_, v_, parts);
  }
}

void BatchDriver::restoreChecked(const CheckpointData& all, const std::vector<SceneSegment>& segments,
                                 const std::vector<PerScene>& per_scene, bool assemble, const std::string& where) {
  const CheckpointData before = batchData();
  const std::vector<SceneSegment> segments_before = segments_;
  const std::vector<PerScene> per_scene_before = per_scene_;
  // L and the factors as they are now, put back bit for bit unless the restore succeeds.
  GlobalSystem::Transaction transaction(system_);
  try {
    apply(all, segments, per_scene, assemble);
  } catch (const Error& e) {
    // What only applying shows (a system that does not factor): the state before goes back
    // (its L and factors, which applying it again would compute anew, are the transaction's).
    apply(before, segments_before, per_scene_before, assemble);
    // The system's refusal names neither the call nor the scene.
    if (dynamic_cast<const InvalidInputError*>(&e) != nullptr) throw InvalidInputError(where + e.what());
    throw;
  }
  transaction.commit();
}

void BatchDriver::restoreScalars(PerScene& p, const CheckpointData& d, double time) {
  p.active = d.time == time;
  static_cast<SceneBook&>(p) = d;
  p.has_user_forces = d.forcing.user_forces.active;
}

void BatchDriver::checkDeviceRange(const CheckpointData& d, const std::string& where) const {
  const double limit = inputLimit(choice_);
  if (!(limit < validation::kMaxMagnitude)) return;
  const MotionState& m = d.motion;
  validation::checkInputRows(m.x, m.x.rows(), where + "positions", limit);
  validation::checkInputRows(m.v, m.v.rows(), where + "velocities", limit);
  if (m.has_history) {
    validation::checkInputRows(m.x_prev, m.x_prev.rows(), where + "previous positions", limit);
    validation::checkInputRows(m.v_prev, m.v_prev.rows(), where + "previous velocities", limit);
  }
  for (std::size_t c = 0; c < d.forcing.colliders.size(); ++c) {
    const Forcing::ColliderMotion& motion = d.forcing.colliders[c];
    const std::string collider = where + "collider " + std::to_string(c) + ": ";
    validation::checkInputVector(motion.start, collider + "position", limit);
    validation::checkInputVector(motion.end, collider + "position", limit);
    validation::checkInputVector(motion.velocity, collider + "velocity", limit);
  }
}

void BatchDriver::restoreScene(int scene, const CheckpointData& d) {
  const RestoreTarget target = restoreTarget(scene, "restore");
  checkRestorable(d, target);
  checkDeviceRange(d, target.where);
  if (d.time != t_)
    throw InvalidInputError(target.where + "the checkpoint is at t = " + timeText(d.time) +
                            ", the batch at t = " + timeText(t_) +
                            ": its scenes share the batch's time, a scene is restored at that time only");
  if (options_.integrator == Integrator::BDF2 && d.motion.has_history != has_history_)
    throw InvalidInputError(target.where +
                            (has_history_ ? "the checkpoint has no BDF2 history, the batch has"
                                          : "the checkpoint has BDF2 history, the batch has none") +
                            ": the batch keeps one for all scenes");
  CheckpointData all = batchData();
  // The scene's contact set as the checkpoint's: its pairs change without the log, so L is then
  // assembled from the flags and factored again, with an empty log.
  const SceneSegment& seg = segments_[std::size_t(scene)];
  const std::size_t cb = std::size_t(contact_.block());
  const bool assemble =
      rangeOf(all.elements.enabled[cb], seg.first_element[cb], seg.num_elements[cb]) != d.elements.enabled[cb];
  std::vector<SceneSegment> segments = segments_;
  splice(all, segments, scene, d, t_);
  if (assemble) all.contact_log.clear();
  std::vector<PerScene> per_scene = per_scene_;
  restoreScalars(per_scene[std::size_t(scene)], d, t_);
  restoreChecked(all, segments, per_scene, assemble, target.where);
}

void BatchDriver::restoreAll(double time, const std::vector<CheckpointData>& scenes) {
  if (int(scenes.size()) != size())
    throw InvalidInputError("restore: the checkpoint has " + std::to_string(scenes.size()) + " scenes, the batch " +
                            std::to_string(size()));
  // A clock that a step no longer moves would leave every scene at one time for ever.
  if (!(time + options_.time_step > time))
    throw InvalidInputError("restore: the checkpoint's time t = " + timeText(time) +
                            " is too large for a step of h = " + timeText(options_.time_step) + " to advance it");
  for (int s = 0; s < size(); ++s) {
    const RestoreTarget target = restoreTarget(s, "restore");
    checkRestorable(scenes[std::size_t(s)], target);
    checkDeviceRange(scenes[std::size_t(s)], target.where);
    if (!(scenes[std::size_t(s)].time <= time))
      throw InvalidInputError(target.where + "its time t = " + timeText(scenes[std::size_t(s)].time) +
                              " is after the batch's, t = " + timeText(time));
  }
  CheckpointData all = batchData();
  all.time = time;
  all.motion.has_history = false;
  all.forcing.user_forces = Forcing::Ramp{};  // the scenes' own ramps only
  std::vector<SceneSegment> segments = segments_;
  std::vector<PerScene> per_scene = per_scene_;
  for (int s = 0; s < size(); ++s) {
    const CheckpointData& d = scenes[std::size_t(s)];
    splice(all, segments, s, d, time);
    restoreScalars(per_scene[std::size_t(s)], d, time);
    // The batch's history is that of its active scenes (an inactive one's is its kept state).
    if (d.time == time) all.motion.has_history = all.motion.has_history || d.motion.has_history;
  }
  all.contact_log = mergeContactLogs(scenes);
  restoreChecked(all, segments, per_scene, /*assemble=*/contact_.count() > 0, "restore: ");
}

// ---- the public classes ----------------------------------------------------------------------------

Checkpoint BatchDriver::checkpointOf(const CheckpointData& all, int scene) const {
  const CheckpointData d = sceneData(all, scene);
  Checkpoint c;
  c.bytes_ = serializeCheckpoint(d);
  c.time_ = d.time;
  c.step_count_ = static_cast<int>(d.steps);
  return c;
}

Checkpoint BatchSimulator::checkpoint(int scene) const {
  impl_->checkScene(scene, "checkpoint");
  return reportingOutOfMemory("BatchSimulator::checkpoint",
                              [&] { return impl_->checkpointOf(impl_->batchData(), scene); });
}

BatchCheckpoint BatchSimulator::checkpoint() const {
  return reportingOutOfMemory("BatchSimulator::checkpoint", [&] {
    const CheckpointData all = impl_->batchData();
    BatchCheckpoint batch;
    batch.time_ = impl_->t_;
    for (int s = 0; s < size(); ++s) batch.scenes_.push_back(impl_->checkpointOf(all, s));
    batch.options_ = recordedOptions(impl_->options_);
    batch.has_options_ = true;
    return batch;
  });
}

void BatchSimulator::restore(int scene, const Checkpoint& checkpoint) {
  reportingOutOfMemory("BatchSimulator::restore",
                       [&] { impl_->restoreScene(scene, parseCheckpoint(checkpoint.bytes(), "restore: checkpoint")); });
}

void BatchSimulator::restore(const BatchCheckpoint& checkpoint) {
  reportingOutOfMemory("BatchSimulator::restore", [&] {
    // A version 1 checkpoint recorded no options: restored unchecked, as it was then.
    if (checkpoint.has_options_) checkSameOptions(checkpoint.options_, impl_->options_);
    std::vector<CheckpointData> scenes;
    for (int s = 0; s < checkpoint.size(); ++s)
      scenes.push_back(
          parseCheckpoint(checkpoint.scene(s).bytes(), "restore: checkpoint of scene " + std::to_string(s)));
    impl_->restoreAll(checkpoint.time(), scenes);
  });
}

}  // namespace stabint
