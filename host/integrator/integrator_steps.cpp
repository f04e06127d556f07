#include "integrator/integrator_steps.hpp"

#include "common/validation.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace stabint {

double solveCoefficient(ImplicitSolve solve, double h) {
  switch (solve) {
    case ImplicitSolve::Midpoint: return 4.0 / (h * h);
    case ImplicitSolve::Bdf2: return 9.0 / (4.0 * h * h);
    case ImplicitSolve::BackwardEuler: break;
  }
  return 1.0 / (h * h);
}

void factorIntegratorSystems(GlobalSystem& system, const SimulatorOptions& options) {
  const double h = options.time_step;
  const auto factor = [&](ImplicitSolve solve, const char* name) { system.factor(solveCoefficient(solve, h), name); };
  switch (options.integrator) {
    case Integrator::BDF2:
      factor(ImplicitSolve::Bdf2, "9/(4 time_step^2)");
      [[fallthrough]];  // and its first step is BE
    case Integrator::BackwardEuler: factor(ImplicitSolve::BackwardEuler, "1/time_step^2"); break;
    case Integrator::EnergyBlend: factor(ImplicitSolve::BackwardEuler, "1/time_step^2"); [[fallthrough]];
    case Integrator::ImplicitMidpoint: factor(ImplicitSolve::Midpoint, "4/time_step^2"); break;
    case Integrator::ForwardEuler:
    case Integrator::SymplecticEuler: break;  // explicit: no system
  }
  if (options.global_solve == GlobalSolve::ConjugateGradient) system.dropFactors();
}

int IntegratorSteps::backwardEuler(double h, double t, int x_out, int v_out, const IterationControl& control,
                                   bool warm_start) {
  backend_.combine(kY, 1.0, kX, h, kV);
  if (!warm_start) backend_.copy(x_out, kY);
  const int done = solver_.solve(solveCoefficient(ImplicitSolve::BackwardEuler, h), kY, x_out, t + h, control);
  potentials_of_step_ = solver_.potentialsOfResult();
  backend_.combine(v_out, 1.0 / h, x_out, -1.0 / h, kX);  // v = (x* - x_n)/h
  return done;
}

int IntegratorSteps::implicitMidpoint(double h, double t, int x_out, int v_out, const IterationControl& control,
                                      int midpoint_out) {
  backend_.combine(kY, 1.0, kX, 0.5 * h, kV);
  backend_.copy(x_out, kY);
  // The solve finds the midpoint and the step extrapolates it, x_1 = 2 x_mid - x_n, doubling
  // its error: L-BFGS ends on a plain iteration, which smooths the error its curvature pairs
  // leave in stiff modes before that doubling turns it into elastic energy.
  const int done =
      solver_.solve(solveCoefficient(ImplicitSolve::Midpoint, h), kY, x_out, t + 0.5 * h, endingPlain(control));
  potentials_of_step_.clear();
  backend_.combine(v_out, 4.0 / h, x_out, -4.0 / h, kX);
  backend_.combine(v_out, 1.0, v_out, -1.0, kV);
  if (midpoint_out >= 0) backend_.copy(midpoint_out, x_out);
  backend_.combine(x_out, 2.0, x_out, -1.0, kX);
  return done;
}

int IntegratorSteps::bdf2(double h, double t, int x_out, int v_out, const IterationControl& control) {
  backend_.combine(kScratch, 4.0 / 3.0, kX, -1.0 / 3.0, kXPrev);
  backend_.combine(kY, 8.0 * h / 9.0, kV, -2.0 * h / 9.0, kVPrev);
  backend_.combine(kY, 1.0, kY, 1.0, kScratch);
  backend_.copy(x_out, kY);
  // BDF2 carries the solve's error into two later steps (x_n and x_{n-1} with weights 4/3 and
  // -1/3) and into v = 3/(2h) (x - ...): L-BFGS's stiff-mode error, left unsmoothed, pumped the
  // teaser's cloth by 0.13 J over 6 s where converged BDF2 loses 0.22 J (with the plain last
  // iteration: loses 0.10 J).
  const int done = solver_.solve(solveCoefficient(ImplicitSolve::Bdf2, h), kY, x_out, t + h, endingPlain(control));
  potentials_of_step_ = solver_.potentialsOfResult();
  backend_.combine(v_out, 1.5 / h, x_out, -1.5 / h, kScratch);
  return done;
}

void IntegratorSteps::explicitEuler(double h, double t, int x_out, int v_out, bool symplectic) {
  potentials_of_step_.clear();
  backend_.accelerations(kScratch, kX, t);
  backend_.combine(v_out, 1.0, kV, h, kScratch);
  backend_.combine(x_out, 1.0, kX, h, symplectic ? v_out : kV);
}

int IntegratorSteps::step(Integrator integrator, double h, double t, bool has_history, int x_out, int v_out,
                          const IterationControl& control) {
  switch (integrator) {
    case Integrator::ForwardEuler: explicitEuler(h, t, x_out, v_out, false); return 0;
    case Integrator::SymplecticEuler: explicitEuler(h, t, x_out, v_out, true); return 0;
    // BDF2's solves keep K_c^-1 as L-BFGS's initial Hessian (control.rigid_modes off): with the
    // rigid motions BDF2 gained energy on the stiff cloth (docs/method.md, "Rigid motions in the
    // initial Hessian"). Implicit midpoint's take them where the driver allows (setRigidModes).
    case Integrator::BackwardEuler: return backwardEuler(h, t, x_out, v_out, control, false);
    case Integrator::BDF2:
      // The first step has no history: BE, as BDF2's.
      return has_history ? bdf2(h, t, x_out, v_out, withoutRigidModes(control))
                         : backwardEuler(h, t, x_out, v_out, withoutRigidModes(control), false);
    case Integrator::ImplicitMidpoint: return implicitMidpoint(h, t, x_out, v_out, control);
    case Integrator::EnergyBlend: break;
  }
  throw Error("IntegratorSteps::step: the blend is the driver's (it decides between steps)");
}

void IntegratorSteps::commit(Integrator integrator, bool& has_history) {
  if (integrator == Integrator::BDF2) {
    backend_.copy(kXPrev, kX);
    backend_.copy(kVPrev, kV);
    has_history = true;
  }
  backend_.copy(kX, kXNew);
  backend_.copy(kV, kVNew);
}

IterationControl iterationControl(const SimulatorOptions& o, int iterations, double energy_scale) {
  IterationControl c;
#define STABINT_COPY_OPTION_(name) c.name = o.name;
  STABINT_SOLVER_OPTION_NAMES(STABINT_COPY_OPTION_)
#undef STABINT_COPY_OPTION_
  c.iterations = iterations;  // the step's budget (setIterations changes it at run time)
  c.energy_scale = energy_scale;
  c.rigid_modes = o.lbfgs_rigid_modes != 0;
  return c;
}

IterationControl endingPlain(IterationControl control) {
  control.plain_last_iteration = true;
  return control;
}

IterationControl withoutRigidModes(IterationControl control) {
  control.rigid_modes = false;
  return control;
}

double forcingWork(const PotentialEnergy& p_new, const PotentialEnergy& new_mid, const PotentialEnergy& old_mid,
                   const PotentialEnergy& p_old) {
  auto forced = [](const PotentialEnergy& p) { return p.pins + p.external; };
  return (forced(p_new) - forced(new_mid)) + (forced(old_mid) - forced(p_old));
}

double initialEnergyScale(double kinetic, const PotentialEnergy& potential, const Eigen::VectorXd& masses,
                          const Eigen::Vector3d& gravity, const Eigen::MatrixX3d& positions) {
  // [project rule] The size is the diagonal of the initial bounding box, not the extent along
  // gravity: a chain released horizontally has zero extent along gravity (and K = E_int = 0),
  // which would make tau zero.
  const double g = gravity.norm();
  const double size =
      positions.rows() > 0 ? (positions.colwise().maxCoeff() - positions.colwise().minCoeff()).norm() : 0.0;
  return kinetic + potential.elastic() + masses.sum() * g * size;
}

double massDot(const Eigen::VectorXd& masses, const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  return (a.cwiseProduct(b).rowwise().sum().array() * masses.array()).sum();
}

double kineticEnergy(const Eigen::VectorXd& masses, const Eigen::MatrixX3d& v) {
  return 0.5 * (v.rowwise().squaredNorm().array() * masses.array()).sum();
}

StepRefusal stepRefusal(int step, double t, double t1, Integrator integrator, const std::string& what,
                        bool energy_limit) {
  // Nothing was committed: the state is the last accepted one, at t. The step is named by its
  // index from 0 (NonFiniteStateError::step()), and labelled so: frames and step counts elsewhere
  // (stabint-run, sweeps) count from 1.
  std::ostringstream msg;
  msg << "step index " << step << " (t = " << t << " -> " << t1 << ", integrator " << integratorName(integrator)
      << "): " << what << (energy_limit ? "; step refused" : "; the simulation blew up, step refused")
      << ", state kept at t = " << t;
  return StepRefusal{msg.str(), energy_limit, step};
}

StepRefusal nonFiniteState(int step, double t, double t1, Integrator integrator) {
  return stepRefusal(step, t, t1, integrator, "non-finite position or velocity", false);
}

StepRefusal checkStepState(int step, double t, double t1, Integrator integrator, const Eigen::MatrixX3d& x,
                           const Eigen::MatrixX3d& v) {
  const double largest = std::max(x.size() ? x.cwiseAbs().maxCoeff() : 0.0, v.size() ? v.cwiseAbs().maxCoeff() : 0.0);
  if (largest <= validation::kMaxMagnitude) return StepRefusal{};
  std::ostringstream what;
  what << "position or velocity " << largest << " beyond " << validation::kMaxMagnitude
       << " in magnitude (the largest state setState and a checkpoint take)";
  return stepRefusal(step, t, t1, integrator, what.str(), false);
}

StepRefusal checkStepEnergy(int step, double t, double t1, const SimulatorOptions& options, double kinetic,
                            const PotentialEnergy& potential, double target, double energy_scale) {
  if (!std::isfinite(kinetic) || !std::isfinite(potential.total()) || !std::isfinite(target))
    return stepRefusal(step, t, t1, options.integrator, "non-finite energy", false);
  // The user's ceiling: an explicit or midpoint run that gains energy is stopped long before it
  // overflows, by the same refusal (docs: SimulatorOptions::energy_limit).
  if (options.energy_limit > 0.0 && kinetic + potential.total() - target > options.energy_limit * energy_scale) {
    std::ostringstream what;
    what << "energy H = " << kinetic + potential.total() << " exceeds the target H* = " << target << " by more than "
         << "energy_limit * E_scale = " << options.energy_limit * energy_scale;
    return stepRefusal(step, t, t1, options.integrator, what.str(), true);
  }
  return StepRefusal{};
}

}  // namespace stabint
