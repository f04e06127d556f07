#include "integrator/batch_simulator.hpp"

#include "integrator/backend_choice.hpp"
#include "integrator/damping.hpp"
#include "integrator/options.hpp"

#include <cmath>
#include <cstddef>
#include <sstream>
#include <utility>

namespace stabint {
namespace {

// Backend slots of the batch (the same roles as Simulator's).
enum Slot : int { kX, kV, kXPrev, kVPrev, kY, kXNew, kVNew, kScratch, kSolverScratch, kNumSlots };

// Simulator's checks, then what the batch does not support yet.
const SimulatorOptions& checkedOptions(const SimulatorOptions& o) {
  validateOptions(o);
  auto fail = [](const std::string& what) { throw InvalidInputError("batch simulator options: " + what); };
  if (o.integrator == Integrator::EnergyBlend)
    fail("the blend is not supported in a batch yet (its decisions per scene: docs/batch_design.md)");
  if (o.tolerance != 0.0 || o.acceleration != Acceleration::None || o.global_solve != GlobalSolve::Factor)
    fail(
        "a tolerance stop, acceleration and CG sum over the whole batch: a fixed iteration count with the factor "
        "only, until they are per scene");
  return o;
}

// The segment's rows as an `n_s by 3` matrix (so that its reductions run as the scene alone's).
Eigen::MatrixX3d rowsOf(const Eigen::MatrixX3d& m, const SceneSegment& s) {
  return m.middleRows(s.first_particle, s.num_particles);
}

}  // namespace

BatchSimulator::BatchSimulator(const std::vector<Scene>& scenes, const SimulatorOptions& options)
    : BatchSimulator(concatenateScenes(scenes), scenes, checkedOptions(options)) {}

BatchSimulator::BatchSimulator(SceneBatch batch, const std::vector<Scene>& scenes, const SimulatorOptions& options)
    : scenes_(scenes),
      segments_(std::move(batch.segments)),
      options_(options),
      data_(batch.scene),
      backend_(makeBackend(data_, kNumSlots, chooseBackend(options_))),
      system_(data_),
      solver_(*backend_, system_, kSolverScratch),
      x_(batch.scene.positions),
      v_(batch.scene.velocities),
      per_scene_(segments_.size()) {
  const double h = options_.time_step;
  // The systems Simulator factors for these integrators, with the same expressions for c.
  if (options_.integrator == Integrator::BDF2) system_.factor(9.0 / (4.0 * h * h), "9/(4 time_step^2)");
  if (options_.integrator == Integrator::BackwardEuler || options_.integrator == Integrator::BDF2)
    system_.factor(1.0 / (h * h), "1/time_step^2");
  if (options_.integrator == Integrator::ImplicitMidpoint) system_.factor(4.0 / (h * h), "4/time_step^2");
  if (!backend_->computesPerScene())
    throw InvalidInputError("batch simulator: " + backend_->description() + " has no per-scene results");
  backend_->setSegments(segments_);
  backend_->write(kX, x_);
  backend_->write(kV, v_);
  std::vector<PotentialEnergy> potentials;
  backend_->potentials(kX, 0.0, potentials);
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    PerScene& p = per_scene_[s];
    p.potential = potentials[s];
    p.kinetic = kineticEnergy(int(s), v_);
    p.target = p.kinetic + p.potential.total();
    // As Simulator's E_scale, from the scene alone.
    const Scene& own = scenes_[s];
    const double size =
        own.numParticles() > 0 ? (own.positions.colwise().maxCoeff() - own.positions.colwise().minCoeff()).norm() : 0.0;
    p.energy_scale = p.kinetic + p.potential.elastic() + own.masses.sum() * own.gravity.norm() * size;
  }
  backend_->times() = PhaseTimes{};
}

double BatchSimulator::kineticEnergy(int scene, const Eigen::MatrixX3d& v) const {
  const SceneSegment& seg = segments_[std::size_t(scene)];
  const Eigen::MatrixX3d rows = rowsOf(v, seg);
  const Eigen::VectorXd masses = data_.masses().segment(seg.first_particle, seg.num_particles);
  return 0.5 * (rows.rowwise().squaredNorm().array() * masses.array()).sum();
}

Eigen::MatrixX3d BatchSimulator::positions(int scene) const { return rowsOf(x_, segments_[std::size_t(scene)]); }
Eigen::MatrixX3d BatchSimulator::velocities(int scene) const { return rowsOf(v_, segments_[std::size_t(scene)]); }
EnergyReport BatchSimulator::energy(int scene) const {
  const PerScene& p = per_scene_[std::size_t(scene)];
  return EnergyReport{p.kinetic, p.potential.elastic(), p.potential.external};
}

const BatchStepReport& BatchSimulator::step() {
  const double h = options_.time_step;
  const double t1 = t_ + h;
  // The integrators as Simulator forms them, on the whole batch.
  IterationControl control;
  control.iterations = options_.iterations;
  int iterations = 0;
  switch (options_.integrator) {
    case Integrator::ForwardEuler:
    case Integrator::SymplecticEuler: {
      const bool symplectic = options_.integrator == Integrator::SymplecticEuler;
      backend_->accelerations(kScratch, kX, t_);
      backend_->combine(kVNew, 1.0, kV, h, kScratch);
      backend_->combine(kXNew, 1.0, kX, h, symplectic ? kVNew : kV);
      break;
    }
    case Integrator::BDF2:
      if (has_history_) {
        backend_->combine(kScratch, 4.0 / 3.0, kX, -1.0 / 3.0, kXPrev);
        backend_->combine(kY, 8.0 * h / 9.0, kV, -2.0 * h / 9.0, kVPrev);
        backend_->combine(kY, 1.0, kY, 1.0, kScratch);
        backend_->copy(kXNew, kY);
        iterations = solver_.solve(9.0 / (4.0 * h * h), kY, kXNew, t1, control);
        backend_->combine(kVNew, 1.5 / h, kXNew, -1.5 / h, kScratch);
        break;
      }
      [[fallthrough]];  // the first step has no history: BE
    case Integrator::BackwardEuler:
      backend_->combine(kY, 1.0, kX, h, kV);
      backend_->copy(kXNew, kY);
      iterations = solver_.solve(1.0 / (h * h), kY, kXNew, t1, control);
      backend_->combine(kVNew, 1.0 / h, kXNew, -1.0 / h, kX);
      break;
    case Integrator::ImplicitMidpoint:
      backend_->combine(kY, 1.0, kX, 0.5 * h, kV);
      backend_->copy(kXNew, kY);
      iterations = solver_.solve(4.0 / (h * h), kY, kXNew, t_ + 0.5 * h, control);
      backend_->combine(kVNew, 4.0 / h, kXNew, -4.0 / h, kX);
      backend_->combine(kVNew, 1.0, kVNew, -1.0, kV);
      backend_->combine(kXNew, 2.0, kXNew, -1.0, kX);
      break;
    case Integrator::EnergyBlend: break;  // refused at construction
  }
  report_.scenes.assign(segments_.size(), StepReport{});
  for (StepReport& r : report_.scenes) r.iterations = iterations;
  report_.refusals.assign(segments_.size(), std::string());

  std::vector<PotentialEnergy> p_new, new_mid, old_mid;
  backend_->potentials(kXNew, t1, p_new);
  // The forcing's work per scene, by Simulator::forcingWork's rule; a scene whose forcing does not
  // change adds exactly 0 (its terms at t_m and t_1 are the same numbers).
  const bool forced = data_.forcingChangesDuring(t_, t1);
  if (forced) {
    const double tm = t_ + 0.5 * h;
    backend_->potentials(kXNew, tm, new_mid);
    backend_->potentials(kX, tm, old_mid);
  }
  backend_->readBoth(kXNew, x_new_, kVNew, v_new_);

  bool rows_changed = false;
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    PerScene& p = per_scene_[s];
    StepReport& r = report_.scenes[s];
    const SceneSegment& seg = segments_[s];
    r.step = p.steps;
    r.time = t1;
    r.energy_evaluations = forced ? 3 : 1;
    auto keepOld = [&] {
      x_new_.middleRows(seg.first_particle, seg.num_particles) = rowsOf(x_, seg);
      v_new_.middleRows(seg.first_particle, seg.num_particles) = rowsOf(v_, seg);
      rows_changed = true;
    };
    if (!p.active) {
      report_.refusals[s] = "inactive since a refused step";
    } else {
      acceptOrRefuse(s, forced ? &new_mid[s] : nullptr, forced ? &old_mid[s] : nullptr, p_new[s], t1, r, rows_changed);
    }
    if (!report_.refusals[s].empty()) {
      p.active = false;
      keepOld();
      r = StepReport{};
      r.step = p.steps;
      r.time = p.time;
    }
    r.energy = EnergyReport{p.kinetic, p.potential.elastic(), p.potential.external};
    r.target = p.target;
  }
  if (rows_changed) {
    backend_->write(kXNew, x_new_);
    backend_->write(kVNew, v_new_);
  }
  if (options_.integrator == Integrator::BDF2) {
    backend_->copy(kXPrev, kX);
    backend_->copy(kVPrev, kV);
    has_history_ = true;
  }
  backend_->copy(kX, kXNew);
  backend_->copy(kV, kVNew);
  x_.swap(x_new_);
  v_.swap(v_new_);
  t_ = t1;
  return report_;
}

// Scene s's candidate (rows of x_new_, v_new_; potential p_new at t1): its forcing work, damping
// and refusal checks as Simulator::step's, and on acceptance its new energies and target.
void BatchSimulator::acceptOrRefuse(std::size_t s, const PotentialEnergy* new_mid, const PotentialEnergy* old_mid,
                                    const PotentialEnergy& p_new, double t1, StepReport& r, bool& rows_changed) {
  PerScene& p = per_scene_[s];
  const SceneSegment& seg = segments_[s];
  double target_now = p.target;
  if (new_mid && std::isfinite(p_new.total())) {
    auto work = [](const PotentialEnergy& e) { return e.pins + e.external; };
    r.forcing = (work(p_new) - work(*new_mid)) + (work(*old_mid) - work(p.potential));
    target_now += r.forcing;
  }
  Eigen::MatrixX3d x_rows = rowsOf(x_new_, seg), v_rows = rowsOf(v_new_, seg);
  std::ostringstream what;
  what << "step " << r.step << " (t = " << t_ << " -> " << t1 << ", integrator " << integratorName(options_.integrator)
       << "): ";
  if (!x_rows.allFinite() || !v_rows.allFinite()) {
    what << "non-finite position or velocity; the simulation blew up, step refused, state kept at t = " << p.time;
    report_.refusals[s] = what.str();
  } else {
    r.damping = applyMomentumPreservingDamping(scenes_[s].bodies, scenes_[s].masses, x_rows, v_rows);
    if (r.damping != 0.0) {
      v_new_.middleRows(seg.first_particle, seg.num_particles) = v_rows;
      rows_changed = true;
    }
    target_now -= r.damping;
    const double k_new = kineticEnergy(int(s), v_new_);
    const double excess = k_new + p_new.total() - target_now;
    if (!std::isfinite(k_new) || !std::isfinite(p_new.total()) || !std::isfinite(target_now)) {
      what << "non-finite energy; the simulation blew up, step refused, state kept at t = " << p.time;
      report_.refusals[s] = what.str();
    } else if (options_.energy_limit > 0.0 && excess > options_.energy_limit * p.energy_scale) {
      what << "energy H = " << k_new + p_new.total() << " exceeds the target H* = " << target_now
           << " by more than energy_limit * E_scale = " << options_.energy_limit * p.energy_scale
           << "; step refused, state kept at t = " << p.time;
      report_.refusals[s] = what.str();
    } else {
      p.kinetic = k_new;
      p.potential = p_new;
      p.target = target_now;
      p.time = t1;
      ++p.steps;
    }
  }
}

}  // namespace stabint
