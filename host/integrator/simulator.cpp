// The integrator driver (method.md sections 2-4), written once against the Backend interface:
// y formation, finalisation, the energy-tracking blend, damping and the per-step bookkeeping.
#include <stabint/simulator.hpp>

#include "backend.hpp"
#include "cpu/cpu_backend.hpp"
#include "integrator/damping.hpp"
#include "integrator/root_find.hpp"
#include "opencl/opencl_backend.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"
#include "solver/local_global.hpp"

#include <chrono>
#include <cmath>
#include <sstream>
#include <vector>

namespace stabint {
namespace {

// Backend state slots used by the driver.
enum Slot : int {
  kX,          // x_n
  kV,          // v_n
  kXPrev,      // x_{n-1} (BDF2)
  kVPrev,      // v_{n-1} (BDF2)
  kY,          // inertial target y of the current solve
  kXNew,       // candidate x_{n+1} (for the blend: the IM candidate, later the blended state)
  kVNew,       // candidate v_{n+1}
  kXPartner,   // BE or FE partner of the blend
  kVPartner,
  kXTrial,     // blended positions during the root find
  kScratch,    // driver scratch
  kSolverScratch,
  kNumSlots
};

void validateOptions(const SimulatorOptions& o) {
  auto fail = [](const std::string& what) { throw InvalidInputError("simulator options: " + what); };
  if (!std::isfinite(o.time_step) || o.time_step <= 0.0)
    fail("time_step = " + std::to_string(o.time_step) + " must be finite and > 0");
  if (o.iterations < 1) fail("iterations = " + std::to_string(o.iterations) + " must be >= 1");
  if (!std::isfinite(o.tolerance) || o.tolerance < 0.0) fail("tolerance must be finite and >= 0");
  if (o.max_iterations < 1) fail("max_iterations must be >= 1");
  if (o.be_iterations < 1) fail("be_iterations = " + std::to_string(o.be_iterations) + " must be >= 1");
  if (!std::isfinite(o.energy_tolerance) || o.energy_tolerance <= 0.0)
    fail("energy_tolerance must be finite and > 0");
  if (!(o.alpha_fe_max > 0.0 && o.alpha_fe_max <= 1.0))
    fail("alpha_fe_max = " + std::to_string(o.alpha_fe_max) + " must be in (0, 1]");
  if (o.max_root_evaluations < 1) fail("max_root_evaluations must be >= 1");
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

bool allFinite(const Eigen::MatrixX3d& m) { return m.allFinite(); }

}  // namespace

struct Simulator::Impl {
  Impl(const Scene& s, const SimulatorOptions& o)
      : options((validateOptions(o), o)),
        scene(s),
        backend(options.backend == BackendKind::OpenCL ? makeOpenCLBackend(scene, kNumSlots, options.opencl)
                                                       : makeCpuBackend(scene, kNumSlots)),
        system(scene),
        solver(*backend, system, kSolverScratch),
        x(s.positions),
        v(s.velocities) {
    backend->write(kX, x);
    backend->write(kV, v);
    potential = backend->potential(kX, 0.0);
    kinetic = kineticEnergy(v);
    target = kinetic + potential.total();
    // E_scale: initial K + E_int plus the work gravity can do on the body, m |g| times its size,
    // so the blend tolerance does not depend on where gravity's zero is. [project rule] The size
    // is the diagonal of the initial bounding box, not the extent along gravity: a chain released
    // horizontally has zero extent along gravity (and K = E_int = 0), which would make tau zero.
    const double g = s.gravity.norm();
    const double size = x.rows() > 0 ? (x.colwise().maxCoeff() - x.colwise().minCoeff()).norm() : 0.0;
    energy_scale = kinetic + potential.elastic() + s.masses.sum() * g * size;
    backend->times() = PhaseTimes{};
  }

  double kineticEnergy(const Eigen::MatrixX3d& vel) const {
    return 0.5 * (vel.rowwise().squaredNorm().array() * scene.masses().array()).sum();
  }

  IterationControl control(int iterations) const {
    return IterationControl{iterations, options.tolerance, options.max_iterations, energy_scale};
  }

  // ---- the integrators: each leaves x_{n+1}, v_{n+1} in (kXNew, kVNew), returns iterations ----

  // x_{n+1} = x* of the solve with c = 1/h^2, y = x_n + h v_n; warm start in `x_out` if
  // `warm_start` is true, else y.
  int backwardEuler(int x_out, int v_out, int iterations, bool warm_start) {
    const double h = options.time_step;
    backend->combine(kY, 1.0, kX, h, kV);
    if (!warm_start) backend->copy(x_out, kY);
    const int done = solver.solve(1.0 / (h * h), kY, x_out, t + h, control(iterations));
    backend->combine(v_out, 1.0 / h, x_out, -1.0 / h, kX);  // v = (x* - x_n)/h
    return done;
  }

  // Midpoint x* of the solve with c = 4/h^2, y = x_n + h/2 v_n, evaluated at t + h/2;
  // x_{n+1} = 2x* - x_n, v_{n+1} = 4(x* - x_n)/h - v_n.
  // When `midpoint_out` is a slot, the midpoint x* is also left there.
  int implicitMidpoint(int x_out, int v_out, int midpoint_out = -1) {
    const double h = options.time_step;
    backend->combine(kY, 1.0, kX, 0.5 * h, kV);
    backend->copy(x_out, kY);
    const int done = solver.solve(4.0 / (h * h), kY, x_out, t + 0.5 * h, control(options.iterations));
    backend->combine(v_out, 4.0 / h, x_out, -4.0 / h, kX);
    backend->combine(v_out, 1.0, v_out, -1.0, kV);
    if (midpoint_out >= 0) backend->copy(midpoint_out, x_out);
    backend->combine(x_out, 2.0, x_out, -1.0, kX);
    return done;
  }

  // c = 9/(4h^2), y = (4x_n - x_{n-1})/3 + (2h/9)(4v_n - v_{n-1});
  // v_{n+1} = 3/(2h) (x* - (4x_n - x_{n-1})/3).
  int bdf2(int x_out, int v_out) {
    const double h = options.time_step;
    backend->combine(kScratch, 4.0 / 3.0, kX, -1.0 / 3.0, kXPrev);
    backend->combine(kY, 8.0 * h / 9.0, kV, -2.0 * h / 9.0, kVPrev);
    backend->combine(kY, 1.0, kY, 1.0, kScratch);
    backend->copy(x_out, kY);
    const int done = solver.solve(9.0 / (4.0 * h * h), kY, x_out, t + h, control(options.iterations));
    backend->combine(v_out, 1.5 / h, x_out, -1.5 / h, kScratch);
    return done;
  }

  // Forward Euler (symplectic = false) or symplectic Euler (true), both with f(x_n, t_n).
  void explicitEuler(int x_out, int v_out, bool symplectic) {
    const double h = options.time_step;
    backend->accelerations(kScratch, kX, t);
    backend->combine(v_out, 1.0, kV, h, kScratch);
    backend->combine(x_out, 1.0, kX, h, symplectic ? v_out : kV);
  }

  // ---- the energy-tracking blend (method.md section 3) ----------------------------------------
  // Leaves the accepted state in (kXNew, kVNew) and returns its potential energy at t + h.
  PotentialEnergy blend(double& target_now, StepReport& report) {
    const double h = options.time_step;
    const double t1 = t + h;
    // The midpoint x* is kept in kXPartner: the forcing work is evaluated there.
    report.iterations += implicitMidpoint(kXNew, kVNew, kXPartner);
    // Forcing at the IM midpoint x* (see forcingWork); the target must include it before the
    // candidate is judged.
    target_now += forcingWork(kXPartner, report);
    const PotentialEnergy p_im = backend->potential(kXNew, t1);
    ++report.energy_evaluations;
    const double vv_im = backend->massDot(kVNew, kVNew);
    const double h_im = 0.5 * vv_im + p_im.total();
    const double tau = options.energy_tolerance * (kinetic + potential.elastic() + energy_scale);

    report.branch = BlendBranch::ImplicitMidpoint;
    report.alpha = 0.0;
    if (std::abs(h_im - target_now) <= tau || !std::isfinite(h_im)) return p_im;

    double alpha_max = 1.0;
    if (h_im > target_now) {
      // Too much energy: backward Euler from (x_n, v_n). [project rule, README "method"] The
      // partner's local/global iterations start at x_n, where the BE objective
      // 1/(2h^2) ||x - x_n - h v_n||_M^2 + E_int + U_ext equals H_n; the iterations never
      // increase it, so however few they are, they cannot pile up elastic energy. method.md
      // warm-starts at x_IM = 2x* - x_n instead, which carries (doubled) the unconverged
      // stretch of the IM solve, and a few BE iterations cannot remove it: measured with
      // be_iterations = 3 on the stiff chain (max |H - H*| 0.37 J at x_IM, 0.19 J at x*,
      // 0.095 J at x_n) and on a falling cloth (7.5 E_avail at x*, 0.011 E_avail at x_n).
      report.branch = BlendBranch::BackwardEuler;
      backend->copy(kXPartner, kX);
      report.iterations += backwardEuler(kXPartner, kVPartner, options.be_iterations, /*warm_start=*/true);
    } else {
      // Too little energy: forward Euler, with its weight capped (see method.md for why).
      report.branch = BlendBranch::ForwardEuler;
      explicitEuler(kXPartner, kVPartner, /*symplectic=*/false);
      alpha_max = options.alpha_fe_max;
    }

    // H(alpha) = K(alpha) + P(alpha). The kinetic part is an exact quadratic in alpha:
    // K = 1/2 (vv + 2 alpha vd + alpha^2 dd) with d = v_partner - v_IM.
    backend->combine(kScratch, 1.0, kVPartner, -1.0, kVNew);
    const KineticQuadratic k_alpha{vv_im, backend->massDot(kVNew, kScratch), backend->massDot(kScratch, kScratch)};
    struct Evaluation {
      double alpha;
      double g;  // H(alpha) - H*
      PotentialEnergy potential;
    };
    std::vector<Evaluation> evaluations;
    auto potentialAt = [&](double alpha) {
      backend->combine(kXTrial, 1.0 - alpha, kXNew, alpha, kXPartner);
      const PotentialEnergy p = backend->potential(kXTrial, t1);
      ++report.energy_evaluations;
      evaluations.push_back({alpha, k_alpha.at(alpha) + p.total() - target_now, p});
      return p.total();
    };

    const double p_max = potentialAt(alpha_max);
    const double g_max = evaluations.front().g;
    const bool partner_cannot_reach_target =
        report.branch == BlendBranch::BackwardEuler ? g_max >= 0.0 : g_max <= 0.0;
    // Otherwise H - H* changes sign on [0, alpha_max]: bracket the root.
    if (!partner_cannot_reach_target && std::abs(g_max) > tau)
      findBlendWeight(k_alpha, potentialAt, target_now, 0.0, p_im.total(), alpha_max, p_max, tau,
                      options.max_root_evaluations);
    Evaluation accepted = evaluations.front();  // alpha_max, taken whole when the target is out of reach
    if (!partner_cannot_reach_target)
      for (const Evaluation& e : evaluations)
        if (std::abs(e.g) < std::abs(accepted.g)) accepted = e;
    const double alpha_best = accepted.alpha;
    const PotentialEnergy p_best = accepted.potential;
    report.alpha = alpha_best;
    backend->combine(kXNew, 1.0 - alpha_best, kXNew, alpha_best, kXPartner);
    backend->combine(kVNew, 1.0 - alpha_best, kVNew, alpha_best, kVPartner);
    return p_best;
  }

  // 1. Forcing: the energy the user puts in through time-dependent potentials (moving pins,
  // changing force fields) during the step, added to H*. [project rule] method.md evaluates
  // U(x, t_{n+1}) - U(x, t_n) at x = x_n. For a pin, U(x, t1) - U(x, t0) = -k dq.(x - q_mid): at
  // x_n that is biased by +k/2 |dq|^2 per step when the particle follows its target, which pumps
  // energy into a cloth dragged by a stiff handle (measured: H* grew to 1000 J in 2 s on
  // scenes/cloth_handle.json with k = 1e5). At the step's midpoint positions the bias cancels
  // (the midpoint rule for the work integral of dU/dt), so we evaluate there: at x* for the blend
  // (the IM midpoint, known before the blend decides) and at (x_n + x_{n+1})/2 otherwise.
  double forcingWork(int midpoint_slot, StepReport& report) {
    if (!scene.hasTimeDependentForcing()) return 0.0;
    const PotentialEnergy before = backend->potential(midpoint_slot, t);
    const PotentialEnergy after = backend->potential(midpoint_slot, t + options.time_step);
    report.energy_evaluations += 2;
    report.forcing = (after.pins + after.external) - (before.pins + before.external);
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
    double target_now = target;

    bool potential_known = false;
    PotentialEnergy p_new;
    switch (options.integrator) {
      case Integrator::ForwardEuler: explicitEuler(kXNew, kVNew, false); break;
      case Integrator::SymplecticEuler: explicitEuler(kXNew, kVNew, true); break;
      case Integrator::BackwardEuler:
        r.iterations = backwardEuler(kXNew, kVNew, options.iterations, false);
        break;
      case Integrator::BDF2:
        // The first step has no history: BE.
        r.iterations = has_history ? bdf2(kXNew, kVNew) : backwardEuler(kXNew, kVNew, options.iterations, false);
        break;
      case Integrator::ImplicitMidpoint: r.iterations = implicitMidpoint(kXNew, kVNew); break;
      case Integrator::EnergyBlend:
        p_new = blend(target_now, r);
        potential_known = true;
        break;
    }
    if (options.integrator != Integrator::EnergyBlend && scene.hasTimeDependentForcing()) {
      backend->combine(kScratch, 0.5, kX, 0.5, kXNew);
      target_now += forcingWork(kScratch, r);
    }

    backend->read(kXNew, x_new);
    backend->read(kVNew, v_new);
    if (!allFinite(x_new) || !allFinite(v_new)) refuse(r, "non-finite position or velocity");

    // Damping acts on the accepted velocities; the energy it removes leaves the target too, so
    // the blend never undoes physical damping.
    r.damping = applyMomentumPreservingDamping(scene.scene().bodies, scene.masses(), x_new, v_new);
    if (r.damping != 0.0) backend->write(kVNew, v_new);
    target_now -= r.damping;

    if (!potential_known) {
      p_new = backend->potential(kXNew, t1);
      ++r.energy_evaluations;
    }
    const double k_new = kineticEnergy(v_new);
    if (!std::isfinite(k_new) || !std::isfinite(p_new.total())) refuse(r, "non-finite energy");

    // Commit.
    if (options.integrator == Integrator::BDF2) {
      backend->copy(kXPrev, kX);
      backend->copy(kVPrev, kV);
      has_history = true;
    }
    backend->copy(kX, kXNew);
    backend->copy(kV, kVNew);
    x.swap(x_new);
    v.swap(v_new);
    t = t1;
    ++steps;
    kinetic = k_new;
    potential = p_new;
    target = target_now;

    r.energy = EnergyReport{kinetic, potential.elastic(), potential.external};
    r.target = target;
    r.times = backend->times();
    r.times.bookkeeping = std::max(0.0, secondsSince(start) - r.times.total());
    report = r;
    return report;
  }

  [[noreturn]] void refuse(const StepReport& r, const std::string& what) {
    // Nothing was committed: the slots kX/kV and the host copies still hold the last finite state.
    std::ostringstream msg;
    msg << "step " << r.step << " (t = " << t << " -> " << r.time << ", integrator "
        << integratorName(options.integrator) << "): " << what
        << "; the simulation blew up, step refused, state kept at t = " << t;
    throw NonFiniteStateError(msg.str(), r.step);
  }

  SimulatorOptions options;
  SceneData scene;
  std::unique_ptr<Backend> backend;
  GlobalSystem system;
  LocalGlobalSolver solver;
  Eigen::MatrixX3d x, v;           // accepted state on the host
  Eigen::MatrixX3d x_new, v_new;   // staging for the candidate
  double t = 0.0;
  int steps = 0;
  bool has_history = false;
  double kinetic = 0.0;
  PotentialEnergy potential;       // of the accepted state at time t
  double target = 0.0;
  double energy_scale = 0.0;
  StepReport report;
};

Simulator::Simulator(const Scene& scene, const SimulatorOptions& options)
    : impl_(std::make_unique<Impl>(scene, options)) {}
Simulator::~Simulator() = default;

const StepReport& Simulator::step() { return impl_->step(); }
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
std::string Simulator::backendDescription() const { return impl_->backend->description(); }

}  // namespace stabint
