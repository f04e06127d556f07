// The driver's contact stages (docs/method.md, "Contact", "Self-contact"): each scene's colliders
// on its own particles (the contact set at the step's start, the pairs' geometry after it,
// friction and the final projection on the candidate, the colliders' share of the forcing),
// self-contact before and after the solve, and the books of all of them.
#include "driver/batch_simulator.hpp"
#include "integrator/integrator_steps.hpp"

#include <string>
#include <vector>

namespace stabint {

ContactPart BatchDriver::contactPart(std::size_t s, int first_row) const {
  const SceneSegment& seg = segments_[s];
  return ContactPart{IndexRange{seg.first_collider, seg.num_colliders}, first_row};
}

double BatchDriver::forcingOfStep(std::size_t s, const PotentialEnergy& p_new, const PotentialEnergy& new_mid,
                                  const PotentialEnergy& old_mid, const Eigen::MatrixX3d& x1) const {
  const PerScene& p = per_scene_[s];
  const double rule = forcingWork(p_new, new_mid, old_mid, p.potential);
  const SceneSegment& seg = segments_[s];
  if (seg.num_colliders == 0) return rule;
  const ContactWork work =
      contactWork(data_, forcing_, contactPart(s, seg.first_particle), t_, options_.time_step, blockOf(x_, seg), x1);
  return rule - work.split + work.midpoint;
}

std::vector<std::size_t> BatchDriver::contactScenes(std::vector<ContactPart>& parts) const {
  std::vector<std::size_t> scenes;
  parts.clear();
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    if (!per_scene_[s].stepping || segments_[s].num_colliders == 0) continue;
    scenes.push_back(s);
    parts.push_back(contactPart(s, 0));
  }
  return scenes;
}

void BatchDriver::updateContactSets() {
  if (contact_.count() == 0) return;
  contact_.forgetReleased();
  std::vector<ContactPart> parts;
  const std::vector<std::size_t> scenes = contactScenes(parts);
  bookContactGeometry(scenes, contact_.updateSet(t_, x_, v_, parts));
}

std::vector<char> BatchDriver::changeContactsInSolve(int slot, const Eigen::MatrixX3d& forces, double t,
                                                     const std::vector<char>& running, bool release) {
  std::vector<ContactPart> parts;
  std::vector<std::size_t> scenes;
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    if (!running[running.size() == 1 ? 0 : s] || !per_scene_[s].stepping || segments_[s].num_colliders == 0) continue;
    scenes.push_back(s);
    parts.push_back(contactPart(s, 0));
  }
  if (parts.empty()) return {};
  backend_->read(slot, x_release_);
  const std::vector<char> changed_parts = release ? contact_.releaseSeparating(t_, x_, v_, t, x_release_, forces, parts)
                                                  : contact_.returnPenetrating(t, x_release_, parts);
  std::vector<char> changed(running.size(), 0);
  for (std::size_t i = 0; i < scenes.size(); ++i)
    if (changed_parts[i]) changed[running.size() == 1 ? 0 : scenes[i]] = 1;
  return changed;
}

void BatchDriver::returnReleasedContacts(const std::vector<char>& scenes) {
  std::vector<ContactPart> parts;
  for (std::size_t s = 0; s < segments_.size(); ++s)
    if (scenes[s] && segments_[s].num_colliders > 0) parts.push_back(contactPart(s, 0));
  if (!parts.empty()) contact_.returnReleased(parts);
}

void BatchDriver::refreshContactGeometry() {
  if (contact_.count() == 0) return;
  std::vector<ContactPart> parts;
  std::vector<std::size_t> scenes = contactScenes(parts);
  std::vector<char> changed = contact_.refreshHalfSpaces(t_, x_, v_, parts);
  // Self-contact's supports hold no energy in the state the step ends with (relaxSupports).
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    if (!per_scene_[s].stepping || segments_[s].support_collider < 0) continue;
    if (!contact_.relaxSupports(segments_[s].support_collider, x_)) continue;
    const auto at = std::lower_bound(scenes.begin(), scenes.end(), s);
    if (at != scenes.end() && *at == s) {
      changed[std::size_t(at - scenes.begin())] = 1;
    } else {
      changed.insert(changed.begin() + (at - scenes.begin()), 1);
      scenes.insert(at, s);
    }
  }
  bookContactGeometry(scenes, changed);
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    if (!changed[i]) continue;
    const PerScene& p = per_scene_[scenes[i]];
    StepReport& r = report_.scenes[scenes[i]];
    r.energy = p.report();
    r.target = p.target;
  }
}

void BatchDriver::bookContactGeometry(const std::vector<std::size_t>& scenes, const std::vector<char>& changed) {
  if (std::find(changed.begin(), changed.end(), 1) == changed.end()) return;
  std::vector<char> which(segments_.size(), 0);
  for (std::size_t i = 0; i < scenes.size(); ++i) which[scenes[i]] = changed[i];
  std::vector<PotentialEnergy> potentials;
  backend_->potentials(kX, t_, potentials, &which);
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    if (!changed[i]) continue;
    PerScene& p = per_scene_[scenes[i]];
    // [project rule] The contact energy of the same positions under the pairs' new geometry: a
    // half-space that follows x lowers it (the collider is convex: its nearest face is never
    // farther than a plane that supports it), and that loss is booked like the final projection's
    // (H and H* move together, now, whether or not the next step is accepted). A pair that
    // entered already inside raises it, and that is not booked: the blend takes it out.
    const double change = std::min(0.0, potentials[scenes[i]].total() - p.potential.total());
    report_.scenes[scenes[i]].contact_projection += change;
    p.target += change;
    p.target_now += change;
    p.potential = potentials[scenes[i]];
  }
}

void BatchDriver::stopSelfContactApproach() {
  if (self_contact_.empty()) return;
  std::vector<ContactResolver::Supports> supports;
  step_supports_.resize(segments_.size());
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    PerScene& p = per_scene_[s];
    if (!p.stepping || self_contact_[s].empty()) continue;
    const SceneSegment& seg = segments_[s];
    const std::vector<int> fixed = pinnedVertices(s);
    const double h = options_.time_step;
    const auto x = blockOf(x_, seg);
    Eigen::MatrixX3d v = blockOf(v_slot_, seg);
    // Where the particles would be at the step's end in free flight, kept out of the colliders
    // (a body resting on the ground stays on it while another falls onto it).
    Eigen::MatrixX3d predicted = x + h * v;
    predicted.rowwise() += (h * h) * scenes_[s].gravity.transpose();
    const ContactPart part = contactPart(s, seg.first_particle);
    contact_.projectOut(part, t_ + h, x, predicted);
    const Eigen::MatrixX3d held = contact_.heldNormals(part, t_ + h, predicted, self_contact_[s].thickness());
    std::vector<SupportPlane>& own = step_supports_[s];
    const double stopped = self_contact_[s].stopApproach(
        x, v, predicted, h, scenes_[s].masses, fixed, solve_supports_[s] ? &own : nullptr, h * h * scenes_[s].gravity,
        options_.self_contact_supports == 2 ? SupportSurfaces::Everywhere : SupportSurfaces::HeavyBodies, &held);
    if (seg.support_collider >= 0) {  // without supports in the solve, none: the relaxation's leave
      std::vector<SupportPlane> planes = own;
      for (SupportPlane& plane : planes) plane.particle += seg.first_particle;
      supports.push_back(ContactResolver::Supports{seg.support_collider, std::move(planes)});
    }
    if (stopped == 0.0) continue;
    // BDF2's history is not the changed state's: this step is a BE step (a batch with BDF2 and
    // self-contact has one scene).
    has_history_ = false;
    // The velocities as the slot holds them (a float device rounds), and the loss they book.
    backend_->roundToStorage(v);
    const double before = p.kinetic;
    v_slot_.middleRows(seg.first_particle, seg.num_particles) = v;
    v_.middleRows(seg.first_particle, seg.num_particles) = v;
    p.kinetic = kineticEnergy(static_cast<int>(s), v_);
    // A loss is booked; a gain (an impulse on a tet body that vibrates against its contact) is
    // not, and the blend takes it out of the step.
    const double removed = std::max(0.0, before - p.kinetic);
    p.target -= removed;
    p.target_now -= removed;
    report_.scenes[s].contact_projection -= removed;
    writeStateRows(seg.first_particle, seg.first_particle + seg.num_particles);
  }
  contact_.setSupports(supports);
}

std::vector<int> BatchDriver::pinnedVertices(std::size_t s) const {
  std::vector<int> pinned;
  for (const Pin& pin : scenes_[s].pins)
    if (pin.stiffness > 0.0) pinned.push_back(pin.vertex);  // a released pin holds nothing
  return pinned;
}

SelfContactResult BatchDriver::resolveSelfContact(std::size_t s, double t1, Eigen::MatrixX3d& x, Eigen::MatrixX3d& v) {
  const SceneSegment& seg = segments_[s];
  const ContactPart part = contactPart(s, seg.first_particle);
  const auto x0 = blockOf(x_, seg);
  const Eigen::MatrixX3d held = contact_.heldNormals(part, t1, x, self_contact_[s].thickness());
  return self_contact_[s].resolve(
      x0, x, v, scenes_[s].masses, pinnedVertices(s),
      [&](Eigen::MatrixX3d& y) { return contact_.projectOut(part, t1, x0, y); }, -scenes_[s].gravity.normalized(),
      &held);
}

double BatchDriver::selfContactGain(std::size_t s, const PotentialEnergy& potential, double kinetic_removed) const {
  return potential.total() - per_scene_[s].p_new.total() - kinetic_removed;
}

void BatchDriver::resolveContact(double t1) {
  if (contact_.count() == 0 && self_contact_.empty()) return;
  std::vector<char> projected(segments_.size(), 0);
  std::vector<ContactResolver::Resolved> moves(segments_.size());
  // Per scene that self-contact moved: the kinetic energy its impulses removed, booked with the
  // potential its moves changed.
  std::vector<char> self_moved(segments_.size(), 0);
  std::vector<double> self_kinetic(segments_.size(), 0.0);
  std::vector<Eigen::MatrixX3d> before_self(segments_.size());  // the candidates self-contact corrected
  bool any = false;
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    PerScene& p = per_scene_[s];
    if (!p.stepping) continue;
    const ContactPart part = contactPart(s, segments_[s].first_particle);
    const auto x0 = blockOf(x_, segments_[s]);
    ContactResolver::Resolved resolved;
    if (contact_.count() > 0)
      resolved = contact_.applyFrictionAndProjection(part, t1, x0, p.x_new, p.v_new, p.target_now, report_.scenes[s]);
    if (!self_contact_.empty() && !self_contact_[s].empty() && self_contact_[s].friction() > 0.0 &&
        !step_supports_[s].empty()) {
      // The supports' friction, booked like the colliders' (a loss, report.friction).
      const std::vector<double> impulses = contact_.supportImpulses(segments_[s].support_collider, step_supports_[s],
                                                                    p.x_new, segments_[s].first_particle);
      const double removed =
          std::max(0.0, self_contact_[s].supportFriction(step_supports_[s], impulses, p.x_new, p.v_new,
                                                         scenes_[s].masses, pinnedVertices(s)));
      report_.scenes[s].friction += removed;
      p.target_now -= removed;
      resolved.velocities_changed = true;
    }
    if (!self_contact_.empty() && !self_contact_[s].empty()) {
      // Self-contact after the colliders' projection; what its impulses take from the motion is
      // lost (inelastic), booked like friction when they moved no position.
      before_self[s] = p.x_new;
      const SelfContactResult r = resolveSelfContact(s, t1, p.x_new, p.v_new);
      resolved.velocities_changed = resolved.velocities_changed || r.velocities_changed;
      resolved.positions_moved = resolved.positions_moved || r.positions_moved;
      self_moved[s] = r.positions_moved;
      restart_history_ = restart_history_ || r.positions_moved || r.velocities_changed;
      if (r.positions_moved) {
        self_kinetic[s] = r.kinetic_removed;
      } else if (r.kinetic_removed > 0.0) {
        p.target_now -= r.kinetic_removed;
        report_.scenes[s].contact_projection -= r.kinetic_removed;
      }
    }
    p.velocities_changed = p.velocities_changed || resolved.velocities_changed;
    if (!resolved.positions_moved) continue;
    moves[s] = resolved;
    if (!any && x_trial_.rows() != x_.rows()) x_trial_ = x_;
    any = true;
    projected[s] = 1;
    x_trial_.middleRows(segments_[s].first_particle, segments_[s].num_particles) = p.x_new;
  }
  if (!any) return;
  // The projected positions as a slot holds them (a float device rounds), and their potentials.
  backend_->roundToStorage(x_trial_);
  backend_->write(kXTrial, x_trial_);
  std::vector<PotentialEnergy> potentials;
  backend_->potentials(kXTrial, t1, potentials, &projected);
  relaxSelfContactPushes(t1, before_self, self_kinetic, potentials);
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    if (!projected[s]) continue;
    PerScene& p = per_scene_[s];
    p.x_new = blockOf(x_trial_, segments_[s]);
    const double before = p.p_new.total();
    double added = 0.0;
    if (self_moved[s]) {
      // [project rule] Self-contact's correction is inelastic and books its net change of H: the
      // kinetic energy its impulses removed less the potential its moves added (a body resting on
      // another falls into the thickness under gravity within the step and is put back, the speed
      // it gained stopped: nothing is lost, where booking the stop alone lowered H* by the
      // speed's energy at every step). Of a net loss, the colliders' restitution keeps its share
      // of what their own moves removed; a net gain is not booked.
      ++report_.scenes[s].energy_evaluations;
      const double change = selfContactGain(s, potentials[s], self_kinetic[s]);
      if (change < 0.0) {
        const double kept = moves[s].kept * std::min(moves[s].removed, -change) / -change;
        report_.scenes[s].contact_projection += change * (1.0 - kept);
        p.target_now += change * (1.0 - kept);
      }
      p.p_new = potentials[s];
      added = std::max(0.0, change);
    } else {
      ContactResolver::bookProjection(potentials[s], moves[s].kept, p.p_new, p.target_now, report_.scenes[s]);
      added = p.p_new.total() - before;
    }
    if (options_.integrator == Integrator::EnergyBlend && added > 0.0 &&
        p.blend.takeOutProjectionExcess(p.x_new, p.v_new, added, p.target_now, p.p_new))
      p.velocities_changed = true;
  }
}

// [project rule] Self-contact's pushes after the solve move the particles they touch and not their
// neighbours: a heavy cloth resting on a soft body that springs back is pushed up where it touches,
// and the stretch around those particles is energy nothing books (39 J in one step of a 30 kg cloth
// on a 1e5 Pa bar, more than its motion held, so H stayed 8.5 bands above H*). So where the pushes
// add more than the scene's band, stretch the elements and contacts by more than it, and leave H
// more than the band above H*, the elements relax around them: each pushed particle keeps a support
// plane through where the push put it, across the push, and the scene is solved for min E(x) + c/2
// |x - x_pushed|_M from x_pushed (c as backward Euler's). The solve only lowers that objective from
// where it starts, on its planes with no support energy, so it adds none; self-contact then runs
// again on the relaxed positions, so that nothing crosses, and the planes are moved out of the
// state (they are the correction's device: a heavy cloth held on them stored joules in them). Up to
// kRelaxRounds rounds, each holding what the last one's pushes moved too, while H stays above its
// band and each takes out at least kRelaxProgress of what the pushes added (a round that lowers H
// less is kept, and the last). The velocities stay the corrected ones. The planes are the scene's
// support collider's (every scene with self-contact has one) and leave at the next step's start
// where the scene takes no supports in the solve. A step that ends below its target relaxes
// nothing: its gain stays within what it damped. Nor does a gain of potential alone: a tet bar
// resting on a cloth sinks within the step and is put back, and relaxing it doubled the iterations
// of its steps and took out nothing.
void BatchDriver::relaxSelfContactPushes(double t1, const std::vector<Eigen::MatrixX3d>& before_self,
                                         std::vector<double>& self_kinetic, std::vector<PotentialEnergy>& potentials) {
  const std::size_t n = segments_.size();
  std::vector<char> relax(n, 0);
  // Per scene its planes so far (each particle's latest) and the positions its last pushes
  // started from.
  std::vector<std::vector<SupportPlane>> planes(n);
  std::vector<Eigen::MatrixX3d> unpushed = before_self;
  for (int round = 0; round < kRelaxRounds; ++round) {
    std::vector<ContactResolver::Supports> supports;
    for (std::size_t s = 0; s < n; ++s) {
      const PerScene& p = per_scene_[s];
      const SceneSegment& seg = segments_[s];
      relax[s] = 0;
      if (!p.stepping || unpushed[s].rows() == 0 || seg.support_collider < 0) continue;
      const double added = selfContactGain(s, potentials[s], self_kinetic[s]);
      const double excess = stabint::kineticEnergy(scenes_[s].masses, p.v_new) + potentials[s].total() - p.target_now;
      const double band = blendTolerance(options_, p.kinetic, p.potential, p.energy_scale);
      // What the pushes stretched: a body lifted whole (one resting on another, put back where it
      // sank within the step) gains potential no relaxing takes out.
      const double stretched = potentials[s].elastic() - p.p_new.elastic();
      if (!(added > band) || !(excess > band) || !(stretched > band)) {
        unpushed[s].resize(0, 3);  // done
        continue;
      }
      if (round == 0) {
        planes[s] = step_supports_[s];
        for (SupportPlane& plane : planes[s]) plane.particle += seg.first_particle;
      }
      holdPushedParticles(seg, unpushed[s], planes[s]);
      supports.push_back(ContactResolver::Supports{seg.support_collider, planes[s]});
      relax[s] = 1;
    }
    if (supports.empty()) return;
    if (!relaxOnce(t1, relax, supports, unpushed, self_kinetic, potentials)) return;
  }
}

// Scene `seg`'s particles that moved from `unpushed` to x_trial_ get a plane through where they
// went, across the move, in `planes` (the concatenation's rows, one per particle).
void BatchDriver::holdPushedParticles(const SceneSegment& seg, const Eigen::MatrixX3d& unpushed,
                                      std::vector<SupportPlane>& planes) const {
  std::vector<int> plane_of(std::size_t(seg.num_particles), -1);
  for (std::size_t k = 0; k < planes.size(); ++k)
    plane_of[std::size_t(planes[k].particle - seg.first_particle)] = int(k);
  for (int j = 0; j < seg.num_particles; ++j) {
    const int row = seg.first_particle + j;
    const Eigen::Vector3d push = (x_trial_.row(row) - unpushed.row(j)).transpose();
    const double length = push.norm();
    if (!(length > 0.0)) continue;
    const SupportPlane plane{
        row, x_trial_.row(row).transpose(), push / length, {row, row, row}, Eigen::Vector3d(1.0, 0.0, 0.0)};
    if (plane_of[std::size_t(j)] >= 0) {
      planes[std::size_t(plane_of[std::size_t(j)])] = plane;
    } else {
      planes.push_back(plane);
    }
  }
}

// One round of relaxSelfContactPushes over the scenes flagged in `relax` (whose planes are
// `supports`): the solve, self-contact again, and the potentials; a scene whose round leaves more
// than it found keeps its pushed state and is done (its `unpushed` emptied), the others' `unpushed`
// become their relaxed positions. Returns whether any scene goes on.
bool BatchDriver::relaxOnce(double t1, const std::vector<char>& relax,
                            const std::vector<ContactResolver::Supports>& supports,
                            std::vector<Eigen::MatrixX3d>& unpushed, std::vector<double>& self_kinetic,
                            std::vector<PotentialEnergy>& potentials) {
  const std::size_t n = segments_.size();
  contact_.setSupports(supports);
  backend_->copy(kY, kXTrial);
  solver_.setSolving(relax);
  const int done = solver_.solve(solveCoefficient(ImplicitSolve::BackwardEuler, options_.time_step), kY, kXTrial, t1,
                                 withoutRigidModes(iterationControl(options_.iterations)));
  const Eigen::MatrixX3d pushed = x_trial_;
  std::vector<Eigen::MatrixX3d> pushed_v(n);
  const std::vector<double> pushed_kinetic = self_kinetic;
  backend_->read(kXTrial, x_trial_);
  for (std::size_t s = 0; s < n; ++s) {
    if (!relax[s]) continue;
    PerScene& p = per_scene_[s];
    const SceneSegment& seg = segments_[s];
    pushed_v[s] = p.v_new;
    report_.scenes[s].iterations += sceneIterations(s, done);
    const ContactPart part = contactPart(s, seg.first_particle);
    const auto x0 = blockOf(x_, seg);
    Eigen::MatrixX3d x1 = blockOf(x_trial_, seg);
    contact_.projectOut(part, t1, x0, x1);
    unpushed[s] = x1;
    self_kinetic[s] += resolveSelfContact(s, t1, x1, p.v_new).kinetic_removed;
    x_trial_.middleRows(seg.first_particle, seg.num_particles) = x1;
  }
  backend_->roundToStorage(x_trial_);
  backend_->write(kXTrial, x_trial_);
  // The planes hold no energy in the state the round ends with: they are the correction's device,
  // not the scene's (what the step's supports held is booked with the pushes' net change).
  for (std::size_t s = 0; s < n; ++s)
    if (relax[s]) contact_.relaxSupports(segments_[s].support_collider, x_trial_);
  std::vector<PotentialEnergy> relaxed;
  backend_->potentials(kXTrial, t1, relaxed, &relax);
  bool undone = false, going_on = false;
  for (std::size_t s = 0; s < n; ++s) {
    if (!relax[s]) continue;
    ++report_.scenes[s].energy_evaluations;
    const double added = selfContactGain(s, potentials[s], pushed_kinetic[s]);
    const double left = selfContactGain(s, relaxed[s], self_kinetic[s]);
    if (left < added) {
      potentials[s] = relaxed[s];
      // Another round where this one took out at least kRelaxProgress of what it found: a heavy
      // body resting on a cloth took out 3 % a round, for a whole solve each.
      if (left <= (1.0 - kRelaxProgress) * added) {
        going_on = true;
      } else {
        unpushed[s].resize(0, 3);
      }
      continue;
    }
    // The relaxed state keeps more than the pushed one (the second pushes undid the relaxation):
    // the pushed state stays.
    PerScene& p = per_scene_[s];
    const SceneSegment& seg = segments_[s];
    x_trial_.middleRows(seg.first_particle, seg.num_particles) =
        pushed.middleRows(seg.first_particle, seg.num_particles);
    p.v_new = pushed_v[s];
    self_kinetic[s] = pushed_kinetic[s];
    unpushed[s].resize(0, 3);
    undone = true;
  }
  if (undone) backend_->write(kXTrial, x_trial_);
  return going_on;
}

}  // namespace stabint
