// The integrator driver (docs/method.md sections 2-8), written once against the Backend interface:
// y formation, finalisation, the energy-tracking blend, damping, the per-step bookkeeping, events
// and checkpoints. It calls, rather than holds, contact (ContactResolver), per-frame input
// (FrameInput) and element changes (ElementChanges).
#include <stabint/simulator.hpp>

#include "backend.hpp"
#include "out_of_memory.hpp"
#include "contact/contact_resolver.hpp"
#include "integrator/backend_choice.hpp"
#include "integrator/blend_step.hpp"
#include "integrator/checkpoint.hpp"
#include "integrator/damping.hpp"
#include "integrator/element_changes.hpp"
#include "integrator/frame_input.hpp"
#include "integrator/integrator_steps.hpp"
#include "integrator/options.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"
#include "solver/local_global.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <vector>

namespace stabint {
namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

struct Simulator::Impl {
  Impl(const Scene& s, const SimulatorOptions& o)
      : options((validateOptions(o), o)),
        scene(s),
        choice(selectBackend(options, sceneSize(s))),
        backend(makeBackend(scene, kNumDriverSlots, choice)),
        system(scene),
        solver(*backend, system, kSolverScratch),
        steps_of(*backend, solver),
        x(s.positions),
        v(s.velocities),
        contact(scene, system, *backend, options, t, x, v),  // the contact set, before anything is factored
        elements(scene, system, *backend),
        input(scene, options.time_step, inputLimit(choice)) {
    // The implicit systems are factored now, so that masses too small for the stiffnesses are
    // refused here, naming them, rather than failing the first step().
    solver.setScene(&scene);
    factorIntegratorSystems(system, options);
    backend->write(kX, x);
    backend->write(kV, v);
    potential = backend->potential(kX, 0.0);
    kinetic = kineticEnergy(v);
    target = kinetic + potential.total();
    energy_scale = initialEnergyScale(kinetic, potential, s.masses, s.gravity, x);
    backend->times() = PhaseTimes{};
  }

  double kineticEnergy(const Eigen::MatrixX3d& vel) const { return stabint::kineticEnergy(scene.masses(), vel); }

  IterationControl control(int iterations) const { return iterationControl(options, iterations, energy_scale); }

  // ---- the integrators (integrator_steps.hpp): each leaves x_{n+1}, v_{n+1} in (x_out, v_out) ----
  int backwardEuler(int x_out, int v_out, int iterations, bool warm_start) {
    return steps_of.backwardEuler(options.time_step, t, x_out, v_out, control(iterations), warm_start);
  }
  int implicitMidpoint(int x_out, int v_out) {
    return steps_of.implicitMidpoint(options.time_step, t, x_out, v_out, control(options.iterations));
  }

  // ---- the energy-tracking blend (docs/method.md, "The blend"; its decisions: blend_step.hpp) --
  // Leaves the blend's positions and IM-or-BE velocities in (kXNew, kVNew) and returns their
  // potential at t + h; the velocity corrections (momenta, energy) follow in step().
  PotentialEnergy blend(double& target_now, StepReport& report) {
    const double t1 = t + options.time_step;
    blend_step.start(BlendScene{&scene.masses(), momentumConserved(), energy_scale, tolerance()}, options, report);
    report.iterations += implicitMidpoint(kXNew, kVNew);
    // The driver needs the candidate on the host whatever the branch (step() for the accepted
    // state, the BE branch for its momenta): read once here, with one wait, and its kinetic
    // energy computed from that copy instead of a device reduction.
    backend->readBoth(kXNew, x_new, kVNew, v_new);
    new_state_on_host = true;
    const PotentialEnergy p_im = backend->potential(kXNew, t1);
    ++report.energy_evaluations;
    const double vv_im = massDot(v_new, v_new);
    if (!std::isfinite(0.5 * vv_im + p_im.total())) {
      // An IM candidate that blew up is no candidate: the step is the BE partner, with the full
      // iteration budget since nothing else of the step is usable.
      new_state_on_host = false;
      blend_step.candidateNotFinite();
      backend->copy(kXNew, kX);
      report.iterations += backwardEuler(kXNew, kVNew, options.iterations, /*warm_start=*/true);
      const PotentialEnergy p_be = potentialOfStep(kXNew, t1, report);
      target_now += forcingWork(kXNew, p_be, report);
      return p_be;
    }
    // The target must include this step's forcing before the candidate is judged.
    target_now += forcingWork(kXNew, p_im, report);
    if (!blend_step.judge(x_new, v_new, p_im, vv_im, target_now)) return p_im;

    backend->copy(kXPartner, kX);
    report.iterations +=
        steps_of.backwardEuler(options.time_step, t, kXPartner, kVPartner, endingPlain(control(options.be_iterations)),
                               /*warm_start=*/true);
    // The partner on the host (one wait): the kinetic quadratic, the blended state and the
    // position move are formed there, which saves two device reductions and the reads of the
    // blended state.
    backend->readBoth(kXPartner, blend_step.partnerPositions(), kVPartner, blend_step.partnerVelocities());
    blend_step.partnerRead();
    evaluateBlendPotentials(t1, steps_of.potentialsOfStep());  // kXNew holds the IM candidate
    const PotentialEnergy p_blend = blend_step.blend(x_new, v_new, *backend);
    backend->write(kXNew, x_new);
    backend->write(kVNew, v_new);
    return p_blend;
  }

  // The potentials the blend asks for, at (1 - w) kXNew + w kXPartner (kXNew holds what
  // BlendStep::from() is). At w = 1 the trial is the partner (0 x + 1 y = y, up to the sign of a
  // zero), whose potential its solve may have left (`partner`): taken without a pass.
  void evaluateBlendPotentials(double t1, const std::vector<PotentialEnergy>& partner = {}) {
    while (blend_step.wantsPotential()) {
      const double w = blend_step.weight();
      if (w == 1.0 && !partner.empty()) {
        blend_step.take(partner[0], /*evaluated=*/false);
        continue;
      }
      backend->combine(kXTrial, 1.0 - w, kXNew, w, kXPartner);
      blend_step.take(backend->potential(kXTrial, t1));
    }
  }

  // The potential at t1 of the step's new positions in `slot`: from the step's solve where its
  // last local step was at them, else an energy pass.
  PotentialEnergy potentialOfStep(int slot, double t1, StepReport& report) {
    if (const std::vector<PotentialEnergy>& p = steps_of.potentialsOfStep(); !p.empty()) return p[0];
    ++report.energy_evaluations;
    return backend->potential(slot, t1);
  }

  double tolerance() const { return blendTolerance(options, kinetic, potential, energy_scale); }

  double massDot(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) const {
    return stabint::massDot(scene.masses(), a, b);
  }

  bool momentumConserved() const { return stabint::momentumConserved(scene.scene(), scene.hasUserForces()); }

  // The blend's corrections of the accepted state (BlendStep::beginCorrections), on the host
  // copies x_new, v_new; the position move toward the partner evaluates its potentials here.
  // Returns true when the velocities changed; p_new follows the positions.
  bool correctBlendState(double target_now, PotentialEnergy& p_new) {
    blend_step.beginCorrections(x_new, v_new, target_now, p_new);
    evaluateBlendPotentials(t + options.time_step);  // kXNew holds the blended positions
    const bool changed = blend_step.finishCorrections(x_new, v_new, p_new, *backend);
    if (blend_step.positionsMoved()) backend->write(kXNew, x_new);
    return changed;
  }

  // Forcing: the energy the user puts in through time-dependent potentials U(x, t) (moving pins,
  // changing force fields) during the step, added to H*. [project rule] The work rule is the one
  // implicit midpoint itself obeys: for U quadratic in x (pins, forces), an IM step satisfies
  //   H_1 - H_0 = [U(x_1, t_1) - U(x_1, t_m)] + [U(x_0, t_m) - U(x_0, t_0)],  t_m = t + h/2,
  // exactly, so a blend that accepts IM tracks H* to round-off whatever path the handle takes.
  // (Evaluating dU at one midpoint position left a ripple of about k h^2 |dq/dt|^2 / 16 on
  // curved handle paths; at x_n it pumped +k/2 |dq|^2 per step.) `x_new` is the step's new
  // positions (the IM candidate for the blend) and `p_new` their potential at t + h.
  double forcingWork(int x_new_slot, const PotentialEnergy& p_new, StepReport& report) {
    if (!scene.forcingChangesDuring(t, t + options.time_step)) return 0.0;
    const double tm = t + 0.5 * options.time_step;
    const PotentialEnergy new_at_midtime = backend->potential(x_new_slot, tm);
    const PotentialEnergy old_at_midtime = backend->potential(kX, tm);
    report.energy_evaluations += 2;
    report.forcing = stabint::forcingWork(p_new, new_at_midtime, old_at_midtime, potential);
    return report.forcing;
  }

  const StepReport& step() {
    const auto start = std::chrono::steady_clock::now();
    backend->times() = PhaseTimes{};
    const double h = options.time_step;
    const double t1 = t + h;
    StepReport r;
    r.step = steps;
    r.time = t1;
    updateContactSet();
    r.event_energy = pending_event_energy;
    double target_now = target;

    PotentialEnergy p_new;
    if (options.integrator == Integrator::EnergyBlend) {
      p_new = blend(target_now, r);
    } else {
      r.iterations = steps_of.step(options.integrator, h, t, has_history, kXNew, kVNew, control(options.iterations));
      p_new = potentialOfStep(kXNew, t1, r);
      if (std::isfinite(p_new.total())) target_now += forcingWork(kXNew, p_new, r);
    }

    // The blend has its state on the host already (the IM candidate it read, or the blend it
    // formed there).
    if (options.integrator != Integrator::EnergyBlend || !new_state_on_host)
      backend->readBoth(kXNew, x_new, kVNew, v_new);
    if (!x_new.allFinite() || !v_new.allFinite()) refuse(nonFiniteState(r.step, t, t1, options.integrator));
    bool velocities_changed = options.integrator == Integrator::EnergyBlend && correctBlendState(target_now, p_new);
    velocities_changed |= contact.resolve(kXNew, t1, x_new, v_new, target_now, p_new, r);

    // Damping acts on the accepted velocities; the energy it removes leaves the target too, so
    // the blend never undoes physical damping.
    r.damping = applyMomentumPreservingDamping(scene.scene().bodies, scene.masses(), x_new, v_new);
    velocities_changed = velocities_changed || r.damping != 0.0;
    if (velocities_changed) {
      backend->roundToStorage(v_new);  // the host copy is what the slot holds (a float device)
      backend->write(kVNew, v_new);
    }
    target_now -= r.damping;

    const double k_new = kineticEnergy(v_new);
    const StepRefusal refusal = checkStepEnergy(r.step, t, t1, options, k_new, p_new, target_now, energy_scale);
    if (!refusal.message.empty()) refuse(refusal);

    // Commit.
    steps_of.commit(options.integrator, has_history);
    x.swap(x_new);
    v.swap(v_new);
    t = t1;
    ++steps;
    kinetic = k_new;
    potential = p_new;
    target = target_now;
    pending_event_energy = 0.0;

    r.energy = EnergyReport{kinetic, potential.elastic(), potential.external};
    r.target = target;
    r.times = backend->times();
    r.times.bookkeeping = std::max(0.0, secondsSince(start) - r.times.total());
    report = r;
    return report;
  }

  // ---- discontinuous events: setState, grab, release, element changes ------------------------
  // H* and the pending event energy move by the jump of H from h_before (the user's work);
  // `kinetic` and `potential` are already those of the new state.
  void bookEvent(double h_before) {
    const double event = kinetic + potential.total() - h_before;
    target += event;
    pending_event_energy += event;
  }

  // A new state: the contact set follows it, BDF2 restarts.
  void setState(const Eigen::MatrixX3d& x_set, const Eigen::MatrixX3d& v_set) {
    input.checkRows(x_set, "positions");
    input.checkRows(v_set, "velocities");
    const double h_before = kinetic + potential.total();
    backend->write(kX, x_set);
    backend->write(kV, v_set);
    // The slots may hold less precision (OpenCL float): the host copies are what they hold.
    backend->read(kX, x);
    backend->read(kV, v);
    updateContactSet();  // so that the event books the contact energy of the new positions
    potential = backend->potential(kX, t);
    kinetic = kineticEnergy(v);
    bookEvent(h_before);
    has_history = false;
  }

  // A change of the elements (`change`, which validates before it changes anything) as an event.
  template <typename Change>
  void changeElementsAsEvent(Change&& change) {
    const double h_before = kinetic + potential.total();
    change();
    potential = backend->potential(kX, t);
    bookEvent(h_before);
  }

  int grab(int vertex, double stiffness) {
    const std::vector<Pin> pins = input.pinsAfterGrab(vertex, stiffness, x);
    changeElementsAsEvent([&] { elements.changePins(pins); });
    return static_cast<int>(pins.size()) - 1;
  }

  void release(int pin) {
    const std::vector<Pin> pins = input.pinsAfterRelease(pin, t);
    changeElementsAsEvent([&] { elements.changePins(pins); });
  }

  void changeElements(ElementKind kind, const std::vector<int>& indices, const double* stiffness, bool enabled) {
    changeElementsAsEvent([&] { elements.change(kind, indices, stiffness, enabled); });
  }

  // The broad phase (ContactResolver::updateSet); a pair that entered inside changed the
  // potential of x.
  void updateContactSet() {
    if (contact.updateSet(t, x, v)) potential = backend->potential(kX, t);
  }

  // ---- checkpoints ------------------------------------------------------------------------------
  CheckpointData checkpointData() const {
    CheckpointData d;
    d.scene_fingerprint = sceneFingerprint(scene.scene());
    d.particles = scene.numParticles();
    d.pins = static_cast<std::int64_t>(scene.scene().pins.size());
    d.pin_list = scene.scene().pins;
    d.time = t;
    d.steps = steps;
    d.target = target;
    d.kinetic = kinetic;
    d.potential = potential;
    d.pending_event_energy = pending_event_energy;
    d.has_history = has_history;
    d.x = x;
    d.v = v;
    backend->read(kXPrev, d.x_prev);
    backend->read(kVPrev, d.v_prev);
    d.forcing = scene.forcingState();
    d.contact_log = contact.log();
    elements.save(d);
    return d;
  }

  // A refused restore changes nothing: what can be checked against the scene is checked first
  // (checkRestorable); what only applying shows (a pin set the scene refuses, stiffnesses whose
  // system does not factor) puts the state taken before back, through the same path.
  void restore(const CheckpointData& d) {
    checkRestorable(d, scene, contact);
    const CheckpointData before = checkpointData();
    try {
      applyCheckpoint(d);
    } catch (const Error&) {
      applyCheckpoint(before);
      throw;
    }
  }

  void applyCheckpoint(const CheckpointData& d) {
    const std::vector<std::uint8_t> contact_base = contact.baseFlags(d.enabled, d.contact_log);
    if (contact.count() == 0) {
      elements.restore(d, contact.block(), nullptr);
    } else {
      // With colliders, L is assembled and factored from the flags of the checkpoint's last
      // assembly and its contact set changes since are replayed (ContactResolver::restore).
      elements.restore(d, contact.block(), &contact_base);
      contact.restore(d.contact_log);
    }
    backend->write(kX, d.x);
    backend->write(kV, d.v);
    backend->write(kXPrev, d.x_prev);
    backend->write(kVPrev, d.v_prev);
    x = d.x;
    v = d.v;
    t = d.time;
    steps = static_cast<int>(d.steps);
    target = d.target;
    kinetic = d.kinetic;
    potential = d.potential;
    pending_event_energy = d.pending_event_energy;
    has_history = d.has_history;
    scene.setForcingState(d.forcing);
    report = StepReport{};
  }

  // Nothing was committed: the slots kX/kV and the host copies still hold the last finite state.
  [[noreturn]] static void refuse(const StepRefusal& refusal) {
    if (refusal.energy_limit) throw EnergyLimitError(refusal.message, refusal.step);
    throw NonFiniteStateError(refusal.message, refusal.step);
  }

  SimulatorOptions options;
  SceneData scene;
  BackendSelection choice;
  std::unique_ptr<Backend> backend;
  GlobalSystem system;
  LocalGlobalSolver solver;
  IntegratorSteps steps_of;
  Eigen::MatrixX3d x, v;          // accepted state on the host
  Eigen::MatrixX3d x_new, v_new;  // staging for the candidate
  double t = 0.0;
  int steps = 0;
  bool has_history = false;
  double kinetic = 0.0;
  PotentialEnergy potential;  // of the accepted state at time t
  double target = 0.0;
  double energy_scale = 0.0;
  BlendStep blend_step;               // the blend's decisions, root finds and corrections
  bool new_state_on_host = false;     // the blend left (x_new, v_new) equal to (kXNew, kVNew)
  double pending_event_energy = 0.0;  // booked by discontinuous input since the last step
  StepReport report;
  ContactResolver contact;  // the contact set; friction and the final projection after the solve
  ElementChanges elements;  // pins, stiffnesses and flags, with L and its factors
  FrameInput input;         // checks and ramps the user's input
};

void Simulator::setElementStiffness(ElementKind kind, int index, double stiffness) {
  impl_->changeElements(kind, {index}, &stiffness, true);
}
void Simulator::setElementStiffness(ElementKind kind, const std::vector<int>& indices, double stiffness) {
  impl_->changeElements(kind, indices, &stiffness, true);
}
void Simulator::setElementEnabled(ElementKind kind, int index, bool enabled) {
  impl_->changeElements(kind, {index}, nullptr, enabled);
}
void Simulator::setElementEnabled(ElementKind kind, const std::vector<int>& indices, bool enabled) {
  impl_->changeElements(kind, indices, nullptr, enabled);
}
bool Simulator::elementEnabled(ElementKind kind, int index) const { return impl_->elements.enabled(kind, index); }

Simulator::Simulator(const Scene& scene, const SimulatorOptions& options)
    : impl_(reportingOutOfMemory("Simulator", [&] { return std::make_unique<Impl>(scene, options); })) {}
Simulator::~Simulator() = default;
Simulator::Simulator(Simulator&&) noexcept = default;
Simulator& Simulator::operator=(Simulator&&) noexcept = default;

const StepReport& Simulator::step() {
  return reportingOutOfMemory("Simulator::step", [&]() -> const StepReport& { return impl_->step(); });
}
const Eigen::MatrixX3d& Simulator::positions() const { return impl_->x; }
const Eigen::MatrixX3d& Simulator::velocities() const { return impl_->v; }
double Simulator::time() const { return impl_->t; }
int Simulator::stepCount() const { return impl_->steps; }
double Simulator::target() const { return impl_->target; }
EnergyReport Simulator::energy() const {
  return EnergyReport{impl_->kinetic, impl_->potential.elastic(), impl_->potential.external};
}
double Simulator::energyScale() const { return impl_->energy_scale; }
const Scene& Simulator::scene() const { return impl_->scene.scene(); }
const SimulatorOptions& Simulator::options() const { return impl_->options; }
const StepReport& Simulator::lastReport() const { return impl_->report; }
std::string Simulator::backendDescription() const {
  const std::string& reason = impl_->choice.reason;
  return impl_->backend->description() + (reason.empty() ? "" : " [" + reason + "]");
}

void Simulator::setPinTarget(int pin, const Eigen::Vector3d& target) {
  impl_->input.setPinTarget(pin, target, impl_->t);
}
Eigen::Vector3d Simulator::pinTarget(int pin) const { return impl_->input.pinTarget(pin, impl_->t); }
void Simulator::setExternalForces(const Eigen::MatrixX3d& forces) { impl_->input.setExternalForces(forces, impl_->t); }
void Simulator::setColliderPosition(int collider, const Eigen::Vector3d& position) {
  impl_->input.setColliderPosition(collider, position, impl_->t);
}
void Simulator::setColliderVelocity(int collider, const Eigen::Vector3d& velocity) {
  impl_->input.setColliderVelocity(collider, velocity, impl_->t);
}
Eigen::Vector3d Simulator::colliderPosition(int collider) const {
  return impl_->input.colliderPosition(collider, impl_->t);
}
Eigen::Vector3d Simulator::colliderVelocity(int collider) const {
  return impl_->input.colliderVelocity(collider, impl_->t);
}
void Simulator::setState(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities) {
  impl_->setState(positions, velocities);
}
void Simulator::setPositions(const Eigen::MatrixX3d& positions) { impl_->setState(positions, impl_->v); }
void Simulator::setVelocities(const Eigen::MatrixX3d& velocities) { impl_->setState(impl_->x, velocities); }
int Simulator::grab(int vertex, double stiffness) { return impl_->grab(vertex, stiffness); }
void Simulator::release(int pin) { impl_->release(pin); }
void Simulator::setIterations(int iterations) {
  if (iterations < 1) throw InvalidInputError("iterations = " + std::to_string(iterations) + " must be >= 1");
  impl_->options.iterations = iterations;
}

Checkpoint Simulator::checkpoint() const {
  Checkpoint c;
  c.bytes_ = serializeCheckpoint(impl_->checkpointData());
  c.time_ = impl_->t;
  c.step_count_ = impl_->steps;
  return c;
}

void Simulator::restore(const Checkpoint& checkpoint) {
  reportingOutOfMemory("Simulator::restore",
                       [&] { impl_->restore(parseCheckpoint(checkpoint.bytes(), "checkpoint")); });
}

}  // namespace stabint
