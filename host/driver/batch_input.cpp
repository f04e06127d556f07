// The batch's per-frame input and element changes (docs/method.md, "Batches"): each call is
// Simulator's (FrameInput, ElementChanges) on one scene's segment, with the scene's indices, and
// what it books is booked in that scene's H* only.
#include "driver/batch_simulator.hpp"

#include "contact/surface_crossings.hpp"
#include "elements/element_type.hpp"
#include "driver/backend_choice.hpp"
#include "integrator/integrator_steps.hpp"

#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

namespace stabint {

InputScope BatchDriver::scope(int scene, const char* call) const {
  checkScene(scene, call);
  // A Simulator's one segment is its whole scene: the same ranges, with Simulator's messages.
  if (as_simulator_) return InputScope();
  return InputScope(segments_[std::size_t(scene)], scene, call);
}

FrameInput BatchDriver::frameInput(int scene, const char* call) {
  return FrameInput(data_, forcing_, options_.time_step, inputLimit(choice_), scope(scene, call));
}

ElementChanges BatchDriver::elementChanges(int scene, const char* call) {
  return ElementChanges(data_, forcing_, system_, *backend_, scope(scene, call));
}

void BatchDriver::bookEvent(int scene, double h_before) {
  PerScene& p = per_scene_[std::size_t(scene)];
  const double event = p.energy() - h_before;
  p.target += event;
  p.pending_event_energy += event;
}

void BatchDriver::checkState(int scene, const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities,
                             const char* call) {
  const FrameInput input = frameInput(scene, call);
  input.checkRows(positions, "positions");
  input.checkRows(velocities, "velocities");
  // BDF2 restarts with a BE step after a jump (its history is not the new state's); the batch keeps
  // one history for all scenes, so only a batch of one can restart.
  if (options_.integrator == Integrator::BDF2 && size() > 1)
    throw InvalidInputError(scope(scene, call).where() +
                            "BDF2 would restart every scene of the batch with a BE step; only a batch of one can");
  if (!self_contact_.empty()) checkNoCrossings(std::size_t(scene), positions, scope(scene, call).where());
}

void BatchDriver::checkNoCrossings(std::size_t s, const Eigen::MatrixX3d& positions, const std::string& where) const {
  const ContactSurface& surface = self_contact_[s].surface();
  const std::vector<std::pair<int, int>> crossing = crossingTriangles(positions, surface.triangles);
  if (crossing.empty()) return;
  auto triangle = [&](int t) {
    const std::array<int, 3>& v = surface.triangles[std::size_t(t)];
    return "surface triangle " + std::to_string(t) + " (particles " + std::to_string(v[0]) + ", " +
           std::to_string(v[1]) + ", " + std::to_string(v[2]) + ")";
  };
  throw InvalidInputError(where + "self-contact: " + triangle(crossing[0].first) + " and " +
                          triangle(crossing[0].second) + " cross (" + std::to_string(crossing.size()) +
                          " crossing pairs in all); self-contact keeps a state free of crossings but cannot undo a "
                          "crossing, so the start must have none (docs/method.md, \"Self-contact\")");
}

double BatchDriver::storeState(int scene, const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities) {
  const SceneSegment& seg = segments_[std::size_t(scene)];
  const PerScene& p = per_scene_[std::size_t(scene)];
  const double h_before = p.energy();
  // The slots may hold less precision (a float device): the host copies are what they hold, the
  // other scenes' rows of kV included (v_slot_, which may differ from their host copies in v_ by
  // round-off, as a Simulator's do).
  if (!host_copies_stored_) {
    backend_->roundToStorage(x_);
    backend_->roundToStorage(v_slot_);
    host_copies_stored_ = true;
  }
  auto store = [&](const Eigen::MatrixX3d& rows, Eigen::MatrixX3d& host) {
    Eigen::MatrixX3d stored = rows;
    backend_->roundToStorage(stored);
    host.middleRows(seg.first_particle, seg.num_particles) = stored;
  };
  store(positions, x_);
  store(velocities, v_slot_);
  v_.middleRows(seg.first_particle, seg.num_particles) = v_slot_.middleRows(seg.first_particle, seg.num_particles);
  return h_before;
}

void BatchDriver::writeStateRows(int first, int end) {
  if (end <= first) return;
  if (backend_->writesRows()) {  // those rows alone, as the host copies hold them
    backend_->writeRows(kX, first, x_.middleRows(first, end - first));
    backend_->writeRows(kV, first, v_slot_.middleRows(first, end - first));
  } else {
    backend_->write(kX, x_);
    backend_->write(kV, v_slot_);
  }
}

void BatchDriver::bookState(int scene, double h_before, const PotentialEnergy& potential) {
  PerScene& p = per_scene_[std::size_t(scene)];
  p.potential = potential;
  p.kinetic = kineticEnergy(scene, v_);
  bookEvent(scene, h_before);
  has_history_ = false;  // BDF2 (a batch of one): the next step is a BE step, as Simulator's
  if (!p.active) {
    p.active = true;
    p.time = t_;
  }
}

void BatchDriver::setState(int scene, const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities) {
  checkState(scene, positions, velocities, "setState");
  settleEvents();  // their potentials are of the positions before
  const double h_before = storeState(scene, positions, velocities);
  const SceneSegment& seg = segments_[std::size_t(scene)];
  writeStateRows(seg.first_particle, seg.first_particle + seg.num_particles);
  // The scene's contact set follows, so that the event books the contact energy of the new
  // positions.
  contact_.updateSet(t_, x_, v_, {contactPart(std::size_t(scene), 0)});
  bookState(scene, h_before, backend_->potentialOf(scene, kX, t_));
}

void BatchDriver::setStates(const std::vector<int>& scenes, const std::vector<Eigen::MatrixX3d>& positions,
                            const std::vector<Eigen::MatrixX3d>& velocities) {
  if (positions.size() != scenes.size() || velocities.size() != scenes.size())
    throw InvalidInputError("setStates: " + std::to_string(scenes.size()) + " scenes, " +
                            std::to_string(positions.size()) + " positions and " + std::to_string(velocities.size()) +
                            " velocities: one of each per scene");
  std::vector<char> listed(std::size_t(size()), 0);
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    checkState(scenes[i], positions[i], velocities[i], "setStates");
    if (listed[std::size_t(scenes[i])]++)
      throw InvalidInputError(scope(scenes[i], "setStates").where() + "listed twice");
  }
  settleEvents();  // their potentials are of the positions before
  // The scenes' events are independent (each books its own H*, each contact set is its scene's),
  // so storing every scene's rows before the contact sets and the potentials changes none of
  // them. One write of the rows from the first listed scene's to the last's (the scenes between
  // rewritten as they are): on a device a write costs a command, whatever its rows.
  std::vector<double> h_before;
  int first = data_.numParticles(), end = 0;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    h_before.push_back(storeState(scenes[i], positions[i], velocities[i]));
    const SceneSegment& seg = segments_[std::size_t(scenes[i])];
    first = std::min(first, seg.first_particle);
    end = std::max(end, seg.first_particle + seg.num_particles);
  }
  writeStateRows(first, end);
  for (int scene : scenes) contact_.updateSet(t_, x_, v_, {contactPart(std::size_t(scene), 0)});
  std::vector<PotentialEnergy> potentials;
  backend_->potentialsOf(scenes, kX, t_, potentials);
  for (std::size_t i = 0; i < scenes.size(); ++i) bookState(scenes[i], h_before[i], potentials[i]);
}

void BatchDriver::setExternalForces(int scene, const Eigen::MatrixX3d& forces) {
  frameInput(scene, "setExternalForces").setExternalForces(forces, t_);
  PerScene& p = per_scene_[std::size_t(scene)];
  p.has_user_forces = true;
  p.momentum_conserved = momentumConserved(scenes_[std::size_t(scene)], p.has_user_forces);
}

void BatchDriver::settleEvents() {
  if (unsettled_.empty()) return;
  // Each scene's potential is its own elements' at its own rows: the other scenes' changes since
  // do not enter it, and potentialsOf gives potentialOf's values bit for bit.
  std::vector<PotentialEnergy> potentials;
  backend_->potentialsOf(unsettled_, kX, t_, potentials);
  for (std::size_t i = 0; i < unsettled_.size(); ++i) {
    PerScene& p = per_scene_[std::size_t(unsettled_[i])];
    p.potential = potentials[i];
    p.event_unsettled = false;
    bookEvent(unsettled_[i], p.h_before_event);
  }
  unsettled_.clear();
}

template <typename Change>
void BatchDriver::changeElementsAsEvent(int scene, const char* call, Change&& change) {
  checkScene(scene, call);
  PerScene& p = per_scene_[std::size_t(scene)];
  if (p.event_unsettled) settleEvents();  // this change's H before is the last one's H after
  const double h_before = p.energy();
  change();
  p.event_unsettled = true;
  p.h_before_event = h_before;
  unsettled_.push_back(scene);
  pinsChanged(scene);
}

int BatchDriver::grab(int scene, int vertex, double stiffness) {
  settleEvents();  // the pin ranges of the later scenes move
  const InputRange own = scope(scene, "grab").pins(data_);
  const std::vector<Pin> pins = frameInput(scene, "grab").pinsAfterGrab(vertex, stiffness, x_);
  changeElementsAsEvent(scene, "grab", [&] {
    elementChanges(scene, "grab").changePins(pins, own.first + own.count);
    // The new pin ends the scene's pin range: the later scenes' ranges move on by one.
    const std::size_t pin_block = std::size_t(data_.blockIndex(pinElementType()));
    ++segments_[std::size_t(scene)].num_elements[pin_block];
    for (std::size_t s = std::size_t(scene) + 1; s < segments_.size(); ++s) ++segments_[s].first_element[pin_block];
    backend_->setSegments(segments_);
  });
  return own.count;
}

void BatchDriver::release(int scene, int pin) {
  settleEvents();  // the pin block is rebuilt
  const std::vector<Pin> pins = frameInput(scene, "release").pinsAfterRelease(pin, t_);
  changeElementsAsEvent(scene, "release", [&] { elementChanges(scene, "release").changePins(pins); });
}

void BatchDriver::changeElements(int scene, ElementKind kind, const std::vector<int>& indices, const double* stiffness,
                                 bool enabled) {
  const char* call = stiffness ? "setElementStiffness" : "setElementEnabled";
  changeElementsAsEvent(scene, call, [&] { elementChanges(scene, call).change(kind, indices, stiffness, enabled); });
}

void BatchDriver::pinsChanged(int scene) {
  const SceneSegment& seg = segments_[std::size_t(scene)];
  const std::size_t pin_block = std::size_t(data_.blockIndex(pinElementType()));
  const std::vector<Pin>& all = data_.scene().pins;
  Scene& own = scenes_[std::size_t(scene)];
  own.pins.assign(all.begin() + seg.first_element[pin_block],
                  all.begin() + seg.first_element[pin_block] + seg.num_elements[pin_block]);
  for (Pin& pin : own.pins) pin.vertex -= seg.first_particle;
  PerScene& p = per_scene_[std::size_t(scene)];
  p.momentum_conserved = momentumConserved(own, p.has_user_forces);
}

// ---- the public class's input ----------------------------------------------------------------

void BatchSimulator::setState(int scene, const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities) {
  impl_->setState(scene, positions, velocities);
}
void BatchSimulator::setStates(const std::vector<int>& scenes, const std::vector<Eigen::MatrixX3d>& positions,
                               const std::vector<Eigen::MatrixX3d>& velocities) {
  impl_->setStates(scenes, positions, velocities);
}
void BatchSimulator::setIterations(int iterations) { impl_->setIterations(iterations); }
void BatchSimulator::setPinTarget(int scene, int pin, const Eigen::Vector3d& target) {
  impl_->frameInput(scene, "setPinTarget").setPinTarget(pin, target, impl_->time());
}
Eigen::Vector3d BatchSimulator::pinTarget(int scene, int pin) const {
  return impl_->frameInput(scene, "pinTarget").pinTarget(pin, impl_->time());
}
void BatchSimulator::setExternalForces(int scene, const Eigen::MatrixX3d& forces) {
  impl_->setExternalForces(scene, forces);
}
void BatchSimulator::setColliderPosition(int scene, int collider, const Eigen::Vector3d& position) {
  impl_->frameInput(scene, "setColliderPosition").setColliderPosition(collider, position, impl_->time());
}
void BatchSimulator::setColliderVelocity(int scene, int collider, const Eigen::Vector3d& velocity) {
  impl_->frameInput(scene, "setColliderVelocity").setColliderVelocity(collider, velocity, impl_->time());
}
Eigen::Vector3d BatchSimulator::colliderPosition(int scene, int collider) const {
  return impl_->frameInput(scene, "colliderPosition").colliderPosition(collider, impl_->time());
}
Eigen::Vector3d BatchSimulator::colliderVelocity(int scene, int collider) const {
  return impl_->frameInput(scene, "colliderVelocity").colliderVelocity(collider, impl_->time());
}
int BatchSimulator::grab(int scene, int vertex, double stiffness) { return impl_->grab(scene, vertex, stiffness); }
void BatchSimulator::release(int scene, int pin) { impl_->release(scene, pin); }
void BatchSimulator::setElementStiffness(int scene, ElementKind kind, int index, double stiffness) {
  impl_->changeElements(scene, kind, {index}, &stiffness, true);
}
void BatchSimulator::setElementStiffness(int scene, ElementKind kind, const std::vector<int>& indices,
                                         double stiffness) {
  impl_->changeElements(scene, kind, indices, &stiffness, true);
}
void BatchSimulator::setElementEnabled(int scene, ElementKind kind, int index, bool enabled) {
  impl_->changeElements(scene, kind, {index}, nullptr, enabled);
}
void BatchSimulator::setElementEnabled(int scene, ElementKind kind, const std::vector<int>& indices, bool enabled) {
  impl_->changeElements(scene, kind, indices, nullptr, enabled);
}
bool BatchSimulator::elementEnabled(int scene, ElementKind kind, int index) const {
  return impl_->elementChanges(scene, "elementEnabled").enabled(kind, index);
}

}  // namespace stabint
