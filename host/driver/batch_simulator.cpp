#include "driver/batch_simulator.hpp"

#include "integrator/damping.hpp"
#include "integrator/integrator_steps.hpp"
#include "driver/options.hpp"
#include "common/validation.hpp"
#include "scene/connected_bodies.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace stabint {
namespace {

// Simulator's checks. Nothing in the options couples the scenes of a batch: every acceleration's
// reductions, safeguards, line searches and stops are per scene, and CG runs on each scene's block
// of the system (on the host, GlobalSystem::setBlocks). The backend is refused later, once
// created, unless it computes per-scene energies (Backend::computesPerScene).
const SimulatorOptions& checkedOptions(const SimulatorOptions& o) {
  validateOptions(o);
  return o;
}

// Self-contact's supports in the solve (docs/method.md, "Self-contact", "Within the solve"): which
// scenes take them. On every surface (2), each scene; on heavy bodies (1, the default), a scene
// with a tet body and particles of no tet (a cloth that may rest on the body).
std::vector<char> solveSupports(const std::vector<Scene>& scenes, const SimulatorOptions& o) {
  std::vector<char> supported(scenes.size(), 0);
  if (!(o.self_contact_thickness > 0.0) || o.self_contact_supports == 0) return supported;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const Scene& s = scenes[i];
    if (o.self_contact_supports == 2) {
      supported[i] = 1;
      continue;
    }
    std::vector<char> in_tet(std::size_t(s.numParticles()), 0);
    for (const Tet& t : s.tets)
      for (int v : t.vertices) in_tet[std::size_t(v)] = 1;
    supported[i] = !s.tets.empty() && std::find(in_tet.begin(), in_tet.end(), 0) != in_tet.end();
  }
  return supported;
}

// Every scene with self-contact gets a support collider: its planes are the supports in the solve
// (solveSupports) and those the pushes after the solve relax on (relaxSelfContactPushes).
SceneBatch batchOf(const std::vector<Scene>& scenes, const SimulatorOptions& o, bool one) {
  if (o.self_contact_thickness > 0.0) return withSupportColliders(scenes, std::vector<char>(scenes.size(), 1), one);
  return one ? batchOfOne(scenes.front()) : concatenateScenes(scenes);
}

// As a matrix, for the public per-scene copies.
Eigen::MatrixX3d rowsOf(const Eigen::MatrixX3d& m, const SceneSegment& s) { return blockOf(m, s); }

}  // namespace

BatchDriver::BatchDriver(const std::vector<Scene>& scenes, const SimulatorOptions& options)
    : BatchDriver(batchOf(scenes, checkedOptions(options), false), scenes, options) {}

std::unique_ptr<BatchDriver> BatchDriver::forSimulator(const Scene& scene, const SimulatorOptions& options) {
  // Simulator's order of checks: the options, then the scene (SceneData validates it, with
  // Simulator's messages).
  validateOptions(options);
  // Its constructor from a batch is the driver's own (private): make_unique cannot reach it.
  std::unique_ptr<BatchDriver> impl(
      new BatchDriver(batchOf({scene}, options, true), std::vector<Scene>{scene}, options));
  impl->as_simulator_ = true;
  return impl;
}

BatchDriver::BatchDriver(SceneBatch batch, const std::vector<Scene>& scenes, const SimulatorOptions& options)
    : scenes_(scenes),
      segments_(std::move(batch.segments)),
      options_(options),
      data_(batch.scene),
      forcing_(data_.scene()),
      choice_(selectBackend(options_, sceneSize(batch.scene))),
      backend_(makeBackend(data_, forcing_, kNumDriverSlots, choice_)),
      system_(data_),
      solver_(*backend_, system_, kSolverScratch),
      x_(batch.scene.positions),
      v_(batch.scene.velocities),
      v_slot_(batch.scene.velocities),
      contact_(data_, forcing_, system_, options_, 0.0, x_, v_),  // the contact set, before anything is factored
      per_scene_(segments_.size()),
      solve_supports_(solveSupports(scenes, options)) {
  if (options_.self_contact_thickness > 0.0) {
    if (options_.integrator == Integrator::BDF2 && scenes_.size() > 1)
      throw InvalidInputError(
          "self_contact_thickness: BDF2 restarts with a BE step where self-contact acts, which would restart every "
          "scene of the batch; only a batch of one can");
    for (std::size_t s = 0; s < scenes_.size(); ++s) {
      self_contact_.emplace_back(scenes_[s], options_.self_contact_thickness, options_.self_contact_friction);
      checkNoCrossings(s, scenes_[s].positions, "scene " + std::to_string(s) + ": ");
    }
  }
  // A float device holds coordinates and speeds up to validation::kMaxMagnitudeFloat, not the
  // scene's 1e150: beyond it a scene lost its speeds in its first step, silently.
  const double limit = inputLimit(choice_);
  for (std::size_t s = 0; limit < validation::kMaxMagnitude && s < scenes_.size(); ++s) {
    const Scene& own = scenes_[s];
    const std::string where = "scene " + std::to_string(s) + ": ";
    validation::checkInputRows(own.positions, own.positions.rows(), where + "positions", limit);
    validation::checkInputRows(own.velocities, own.velocities.rows(), where + "velocities", limit);
    for (std::size_t c = 0; c < own.colliders.size(); ++c) {
      const std::string collider = where + "collider " + std::to_string(c) + ": ";
      validation::checkInputVector(own.colliders[c].center, collider + "center", limit);
      validation::checkInputVector(own.colliders[c].velocity, collider + "velocity", limit);
    }
  }
  // Any backend with per-scene energies steps a batch (the OpenCL backend once it has them).
  if (!backend_->computesPerScene())
    throw InvalidInputError("batch simulator: the backend (" + backend_->description() +
                            ") computes no per-scene energies yet (docs/batch_design.md)");
  solver_.setScene(data_, forcing_);  // Newton-CG's spring Hessians, the rigid motions' one-particle elements
  if (contact_.count() > 0 && options_.contact_release != 0)
    solver_.setContactChange([this](int slot, const Eigen::MatrixX3d& forces, double t,
                                    const std::vector<char>& running,
                                    bool release) { return changeContactsInSolve(slot, forces, t, running, release); });
  factorIntegratorSystems(system_, options_);
  backend_->setSegments(segments_);
  backend_->write(kX, x_);
  backend_->write(kV, v_);
  std::vector<PotentialEnergy> potentials;
  backend_->potentials(kX, 0.0, potentials);
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    PerScene& p = per_scene_[s];
    p.potential = potentials[s];
    p.kinetic = kineticEnergy(int(s), v_);
    p.target = p.energy();
    const Scene& own = scenes_[s];
    p.energy_scale = initialEnergyScale(p.kinetic, p.potential, own.masses, own.gravity, own.positions);
    p.momentum_conserved = momentumConserved(own, /*has_user_forces=*/false);
    p.bodies = connectedBodies(own);
    if (p.bodies.size() == 1) p.bodies.clear();
  }
  std::vector<double> energy_scales;
  for (const PerScene& p : per_scene_) energy_scales.push_back(p.energy_scale);
  solver_.setSegments(segments_, energy_scales);
  backend_->times() = PhaseTimes{};
}

double BatchDriver::kineticEnergy(int scene, const Eigen::MatrixX3d& v) const {
  const SceneSegment& seg = segments_[std::size_t(scene)];
  return stabint::kineticEnergy(scenes_[std::size_t(scene)].masses, rowsOf(v, seg));
}

const Scene& BatchDriver::publicScene() const {
  if (segments_.front().support_collider < 0) return data_.scene();
  public_scene_ = data_.scene();
  public_scene_.colliders.pop_back();
  return public_scene_;
}

Eigen::MatrixX3d BatchDriver::positions(int scene) const { return rowsOf(x_, segments_[std::size_t(scene)]); }
Eigen::MatrixX3d BatchDriver::velocities(int scene) const { return rowsOf(v_, segments_[std::size_t(scene)]); }
EnergyReport BatchDriver::energy(int scene) {
  settleEvents();
  const PerScene& p = per_scene_[std::size_t(scene)];
  return p.report();
}
double BatchDriver::target(int scene) {
  settleEvents();
  return per_scene_[std::size_t(scene)].target;
}

void BatchDriver::checkScene(int scene, const char* call) const {
  if (scene < 0 || scene >= size())
    throw InvalidInputError(std::string(call) + ": scene " + std::to_string(scene) + " out of range (the batch has " +
                            std::to_string(size()) + " scenes)");
}

void BatchDriver::refuse(std::size_t s, const StepRefusal& refusal) {
  // A Simulator's driver: nothing was committed yet (the slots kX/kV, the host copies, the BDF2
  // history, H* and the time still hold the last accepted step), so the Simulator can step again.
  if (as_simulator_) {
    if (refusal.energy_limit) throw EnergyLimitError(refusal.message, refusal.step);
    throw NonFiniteStateError(refusal.message, refusal.step);
  }
  report_.refusals[s] = refusal.message;
  per_scene_[s].stepping = false;
}

void BatchDriver::setIterations(int iterations) {
  if (iterations < 1) throw InvalidInputError("iterations = " + std::to_string(iterations) + " must be >= 1");
  options_.iterations = iterations;
}

std::string BatchDriver::backendDescription() const {
  const std::string& reason = choice_.reason;
  return backend_->description() + (reason.empty() ? "" : " [" + reason + "]");
}

const BatchStepReport& BatchDriver::step() {
  settleEvents();  // before the step's clock and phase times, as when each change settled at once
  const auto start = std::chrono::steady_clock::now();
  backend_->times() = PhaseTimes{};
  const double h = options_.time_step;
  const double t1 = t_ + h;
  restart_history_ = false;  // a refused step's flag does not carry over
  startScenes(t1);
  stopSelfContactApproach();
  updateContactSets();
  // The forcing's work per scene, by Simulator's rule; a scene whose forcing does not change adds
  // exactly 0 (its terms at t_m and t_1 are the same numbers).
  const std::vector<char> forced_scenes = forcing_.changesDuring(t_, t1, segments_);
  const bool forced = std::any_of(forced_scenes.begin(), forced_scenes.end(), [](char f) { return f != 0; });
  // The blend partner's solves take the rigid motions into L-BFGS's initial Hessian only in the
  // scenes whose forcing is constant over the step (docs/method.md, "Rigid motions in the initial
  // Hessian"): with them a dragged cloth's partner lagged behind the hand with more elastic energy
  // than the forcing booked, and the blend left its band. Implicit midpoint's: midpointRigidMotions.
  std::vector<char> steady(forced_scenes.size());
  for (std::size_t s = 0; s < steady.size(); ++s) steady[s] = forced_scenes[s] ? 0 : 1;
  if (options_.integrator == Integrator::EnergyBlend)
    blend(t1, forced, steady);
  else
    integrate(t1, forced, steady);

  for (std::size_t s = 0; s < segments_.size(); ++s) {
    PerScene& p = per_scene_[s];
    if (p.stepping && (!p.x_new.allFinite() || !p.v_new.allFinite()))
      refuse(s, nonFiniteState(report_.scenes[s].step, t_, t1, options_.integrator));
  }
  if (options_.integrator == Integrator::EnergyBlend) {
    for (PerScene& p : per_scene_)
      if (p.stepping) p.blend.beginCorrections(p.x_new, p.v_new, p.target_now, p.p_new);
    evaluateBlendPotentials(t1);
    for (PerScene& p : per_scene_)
      if (p.stepping) p.velocities_changed = p.blend.finishCorrections(p.x_new, p.v_new, p.p_new, *backend_);
  }
  resolveContact(t1);
  acceptScenes(t1);
  commit(t1);
  // The step's times are the batch's (its scenes share every pass); a Simulator reports them as
  // its own step's.
  report_.times = backend_->times();
  report_.times.bookkeeping = std::max(
      0.0, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() - report_.times.total());
  if (as_simulator_) report_.scenes[0].times = report_.times;
  return report_;
}

void BatchDriver::startScenes(double t1) {
  const std::size_t n = segments_.size();
  report_.scenes.assign(n, StepReport{});
  report_.refusals.assign(n, std::string());
  for (std::size_t s = 0; s < n; ++s) {
    PerScene& p = per_scene_[s];
    StepReport& r = report_.scenes[s];
    r.step = static_cast<int>(p.steps);
    r.time = t1;
    r.event_energy = p.pending_event_energy;
    p.stepping = p.active;
    p.velocities_changed = false;
    p.target_now = p.target;
    if (!p.active) report_.refusals[s] = "inactive since a refused step";
  }
}

void BatchDriver::acceptScenes(double t1) {
  const std::size_t n = segments_.size();
  for (std::size_t s = 0; s < n; ++s) {
    PerScene& p = per_scene_[s];
    StepReport& r = report_.scenes[s];
    if (!p.stepping) continue;
    // Damping acts on the accepted velocities; the energy it removes leaves the target too.
    r.damping = applyMomentumPreservingDamping(scenes_[s].bodies, scenes_[s].masses, p.x_new, p.v_new);
    p.velocities_changed = p.velocities_changed || r.damping != 0.0;
    if (p.velocities_changed) backend_->roundToStorage(p.v_new);
    p.target_now -= r.damping;
    const double k_new = stabint::kineticEnergy(scenes_[s].masses, p.v_new);
    StepRefusal refusal = checkStepEnergy(r.step, t_, t1, options_, k_new, p.p_new, p.target_now, p.energy_scale);
    if (refusal.message.empty()) refusal = checkStepState(r.step, t_, t1, options_.integrator, p.x_new, p.v_new);
    if (!refusal.message.empty()) {
      refuse(s, refusal);
      continue;
    }
    p.kinetic = k_new;
    p.potential = p.p_new;
    p.target = p.target_now;
    p.time = t1;
    ++p.steps;
    p.pending_event_energy = 0.0;
  }
}

void BatchDriver::commit(double t1) {
  const std::size_t n = segments_.size();
  // The new state of the batch: each stepped scene's candidate, each other scene's last state
  // (its block took no part in the solves). The slots get the velocities Simulator's
  // slots would hold: the host copy when it changed them (corrections, damping that removed
  // energy), else the solve's (v_new_ mirrors kVNew; damping that removes exactly 0 J may still
  // move the host copy by round-off, and Simulator then keeps the solve's).
  for (std::size_t s = 0; s < n; ++s) {
    PerScene& p = per_scene_[s];
    const SceneSegment& seg = segments_[s];
    StepReport& r = report_.scenes[s];
    if (p.stepping) {
      x_new_.middleRows(seg.first_particle, seg.num_particles) = p.x_new;
      if (p.velocities_changed) v_new_.middleRows(seg.first_particle, seg.num_particles) = p.v_new;
      v_.middleRows(seg.first_particle, seg.num_particles) = p.v_new;
    } else {
      x_new_.middleRows(seg.first_particle, seg.num_particles) = blockOf(x_, seg);
      v_new_.middleRows(seg.first_particle, seg.num_particles) = blockOf(v_slot_, seg);
      p.active = false;
      const double event_energy = r.event_energy;
      r = StepReport{};
      r.step = static_cast<int>(p.steps);
      r.time = p.time;
      r.event_energy = event_energy;
    }
    r.energy = p.report();
    r.target = p.target;
  }
  backend_->write(kXNew, x_new_);
  backend_->write(kVNew, v_new_);
  IntegratorSteps(*backend_, solver_).commit(options_.integrator, has_history_);
  // [project rule] Self-contact's corrections after the solve are no BDF2 step: the next step
  // restarts with a BE step, as after a jump (BDF2 continuing from a history its corrections
  // contradict pumped a cloth dragged over a body to 10^6 J within 6 s).
  if (restart_history_) has_history_ = false;
  restart_history_ = false;
  x_.swap(x_new_);
  v_slot_.swap(v_new_);
  t_ = t1;
  // The pairs' geometry of the new state, so that the params are always the state's (a restore
  // rebuilds them from it) and the step's potential is booked under them.
  refreshContactGeometry();
}

std::vector<char> BatchDriver::steppingScenes() const {
  std::vector<char> stepping(per_scene_.size());
  for (std::size_t s = 0; s < per_scene_.size(); ++s) stepping[s] = per_scene_[s].stepping ? 1 : 0;
  return stepping;
}

int BatchDriver::sceneIterations(std::size_t s, int done) const {
  return done == 0 ? 0 : solver_.segmentIterations(s);  // 0: an explicit step, no solve
}

IterationControl BatchDriver::iterationControl(int iterations) const {
  // A batch of more than one measures each scene against its own scale (LocalGlobalSolver's
  // segments); the whole-vector controls it refuses. A batch of one is its scene.
  return stabint::iterationControl(options_, iterations, per_scene_.size() == 1 ? per_scene_[0].energy_scale : 1.0);
}

// [project rule] Implicit midpoint's solves (the IM integrator's, the blend's candidate) take the
// rigid motions in the scenes whose forcing is constant over the step, and in a forced scene
// without colliders that swings (its kinetic energy above the blend's band) and is not held far
// from its rest shape (its elastic energy, pins included, at most E_scale): a cloth swinging on a
// moving handle then keeps its period, and the handle stops pumping it (docs/method.md, "The
// forced steps of a swinging body"). A hand stretching a cloth against its fixed corners, or
// pulling a body from rest, keeps K_c^-1: the coarse space made such drags gain 2.5-4x their
// references' motion. So does a scene with colliders: on a cloth poked by a moving tool the
// candidate's coarse motion went into the tool, and friction took joules from it at every third
// step. Decided from the scene's book at the step's start, so a checkpoint continues as the run
// did and a batch's scene steps as its own Simulator.
std::vector<char> BatchDriver::midpointRigidMotions(const std::vector<char>& steady) const {
  std::vector<char> rigid = steady;
  for (std::size_t s = 0; s < rigid.size(); ++s) {
    const PerScene& p = per_scene_[s];
    const bool swinging = p.kinetic > blendTolerance(options_, p.kinetic, p.potential, p.energy_scale);
    if (segments_[s].num_colliders == 0 && swinging && p.potential.elastic() <= p.energy_scale) rigid[s] = 1;
  }
  return rigid;
}

void BatchDriver::integrate(double t1, bool forced, const std::vector<char>& steady) {
  const double h = options_.time_step;
  const IterationControl control = iterationControl(options_.iterations);
  IntegratorSteps steps(*backend_, solver_);
  const std::vector<char> stepping = steppingScenes();
  solver_.setSolving(stepping);
  if (options_.integrator == Integrator::ImplicitMidpoint) solver_.setRigidModes(midpointRigidMotions(steady));
  const int iterations = steps.step(options_.integrator, h, t_, has_history_, kXNew, kVNew, control);
  const bool evaluated = potentialsOfStep(steps, kXNew, t1, stepping);
  if (forced) {
    backend_->potentials(kXNew, t_ + 0.5 * h, new_mid_, &stepping);
    backend_->potentials(kX, t_ + 0.5 * h, old_mid_, &stepping);
  }
  backend_->readBoth(kXNew, x_new_, kVNew, v_new_);
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    PerScene& p = per_scene_[s];
    if (!p.stepping) continue;
    StepReport& r = report_.scenes[s];
    r.iterations = sceneIterations(s, iterations);
    r.energy_evaluations = evaluated ? 1 : 0;
    p.x_new = blockOf(x_new_, segments_[s]);
    p.v_new = blockOf(v_new_, segments_[s]);
    p.p_new = p_all_[s];
    if (forced && std::isfinite(p.p_new.total())) {
      r.forcing = forcingOfStep(s, p.p_new, new_mid_[s], old_mid_[s], p.x_new);
      r.energy_evaluations += 2;
      p.target_now += r.forcing;
    }
  }
}

// The potentials of the step's new positions in `slot` at t1, of the scenes flagged in `which`
// (those the step solved), into p_all_: the step's solve's where its last local step was at them,
// else an energy pass (returns whether it ran).
bool BatchDriver::potentialsOfStep(const IntegratorSteps& steps, int slot, double t1, const std::vector<char>& which) {
  if (steps.potentialsOfStep().size() == segments_.size()) {
    p_all_ = steps.potentialsOfStep();
    return false;
  }
  backend_->potentials(slot, t1, p_all_, &which);
  return true;
}

}  // namespace stabint
