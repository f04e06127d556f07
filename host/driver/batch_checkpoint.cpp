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
#include "state/checkpoint_slices.hpp"

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

int pinBlock(const SceneData& data) { return data.blockIndex(pinElementType()); }

// An option's value as a batch checkpoint records it: a double to the bit (17 digits), an int
// in decimal, an enum by its name.
std::string optionText(double value) { return exactText(value); }
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
    throw InvalidInputError(target.where + "the checkpoint is at t = " + exactText(d.time) +
                            ", the batch at t = " + exactText(t_) +
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
  spliceScene(all, segments, scene, pinBlock(data_), d, t_, scenes_[std::size_t(scene)].colliders, target.where);
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
    throw InvalidInputError("restore: the checkpoint's time t = " + exactText(time) +
                            " is too large for a step of h = " + exactText(options_.time_step) + " to advance it");
  for (int s = 0; s < size(); ++s) {
    const RestoreTarget target = restoreTarget(s, "restore");
    checkRestorable(scenes[std::size_t(s)], target);
    checkDeviceRange(scenes[std::size_t(s)], target.where);
    if (!(scenes[std::size_t(s)].time <= time))
      throw InvalidInputError(target.where + "its time t = " + exactText(scenes[std::size_t(s)].time) +
                              " is after the batch's, t = " + exactText(time));
  }
  CheckpointData all = batchData();
  all.time = time;
  all.motion.has_history = false;
  all.forcing.user_forces = Forcing::Ramp{};  // the scenes' own ramps only
  std::vector<SceneSegment> segments = segments_;
  std::vector<PerScene> per_scene = per_scene_;
  for (int s = 0; s < size(); ++s) {
    const CheckpointData& d = scenes[std::size_t(s)];
    spliceScene(all, segments, s, pinBlock(data_), d, time, scenes_[std::size_t(s)].colliders,
                restoreTarget(s, "restore").where);
    restoreScalars(per_scene[std::size_t(s)], d, time);
    // The batch's history is that of its active scenes (an inactive one's is its kept state).
    if (d.time == time) all.motion.has_history = all.motion.has_history || d.motion.has_history;
  }
  all.contact_log = mergeContactLogs(scenes, segments_, contact_.block());
  restoreChecked(all, segments, per_scene, /*assemble=*/contact_.count() > 0, "restore: ");
}

// ---- the public classes ----------------------------------------------------------------------------

Checkpoint BatchDriver::checkpointOf(const CheckpointData& all, int scene) const {
  const PerScene& p = per_scene_[std::size_t(scene)];
  const CheckpointData d = cutScene(all, SceneSlice{segments_[std::size_t(scene)], pinBlock(data_), contact_.block()},
                                    sceneFingerprint(scenes_[std::size_t(scene)]), p, p.active, p.has_user_forces);
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
    batch.time_ = impl_->time();
    for (int s = 0; s < size(); ++s) batch.scenes_.push_back(impl_->checkpointOf(all, s));
    batch.options_ = recordedOptions(impl_->options());
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
    if (checkpoint.has_options_) checkSameOptions(checkpoint.options_, impl_->options());
    std::vector<CheckpointData> scenes;
    for (int s = 0; s < checkpoint.size(); ++s)
      scenes.push_back(
          parseCheckpoint(checkpoint.scene(s).bytes(), "restore: checkpoint of scene " + std::to_string(s)));
    impl_->restoreAll(checkpoint.time(), scenes);
  });
}

}  // namespace stabint
