#pragma once
// The integrators' formulas, written once over (Backend&, slots) for every driver that steps a
// scene with them (Simulator, BatchSimulator), so that the two cannot drift: the systems each
// integrator factors, the y each forms, the velocity update after the solve, the forcing rule,
// E_scale and the refusal messages (docs/method.md sections 2, 4, 7 and 8).
#include "backend/backend.hpp"
#include "solver/global_system.hpp"
#include "solver/local_global.hpp"

#include <stabint/types.hpp>

#include <Eigen/Core>

#include <optional>
#include <string>

namespace stabint {

/// Backend slots of a driver (the same roles in every driver).
enum DriverSlot : int {
  kX,         // x_n
  kV,         // v_n
  kXPrev,     // x_{n-1} (BDF2)
  kVPrev,     // v_{n-1} (BDF2)
  kY,         // inertial target y of the current solve
  kXNew,      // candidate x_{n+1} (for the blend: the IM candidate, later the blended state)
  kVNew,      // candidate v_{n+1}
  kXPartner,  // BE partner of the blend
  kVPartner,
  kXTrial,   // blended positions during the root find
  kScratch,  // driver scratch
  kSolverScratch,
  kNumDriverSlots
};

/// The implicit solves the integrators run: backward Euler's (BDF2's first step and the blend's
/// partner too), implicit midpoint's (for its midpoint) and BDF2's.
enum class ImplicitSolve { BackwardEuler, Midpoint, Bdf2 };
/// The solve's coefficient c of K_c = c M + L at step h: 1/h^2, 4/h^2, 9/(4 h^2). The one place
/// the factors and the solves take it from, so that a solve finds its factor by c's exact value.
double solveCoefficient(ImplicitSolve solve, double h);

/// Factors the systems K_c = c M + L the integrator solves with (the blend: BE's and IM's), with
/// c from solveCoefficient as the steps below take it, so that each is factored once. Explicit
/// integrators factor nothing. With GlobalSolve::ConjugateGradient the factors only validate the
/// systems (masses too small for the stiffnesses are refused here, naming them, rather than
/// failing the first step) and are then dropped: element changes would keep updating them for
/// nothing.
void factorIntegratorSystems(GlobalSystem& system, const SimulatorOptions& options);

/// One integrator step from (kX, kV) at time t (and (kXPrev, kVPrev) for BDF2): each leaves
/// x_{n+1}, v_{n+1} in (x_out, v_out) and returns the local/global iterations it did.
class IntegratorSteps {
 public:
  IntegratorSteps(Backend& backend, LocalGlobalSolver& solver) : backend_(backend), solver_(solver) {}

  /// x_{n+1} = x* of the solve with c = 1/h^2, y = x_n + h v_n; warm start in `x_out` when
  /// `warm_start`, else y.
  int backwardEuler(double h, double t, int x_out, int v_out, const IterationControl& control, bool warm_start);
  /// Midpoint x* of the solve with c = 4/h^2, y = x_n + h/2 v_n, evaluated at t + h/2;
  /// x_{n+1} = 2x* - x_n, v_{n+1} = 4(x* - x_n)/h - v_n. When `midpoint_out` is a slot, x* is
  /// also left there.
  int implicitMidpoint(double h, double t, int x_out, int v_out, const IterationControl& control,
                       int midpoint_out = -1);
  /// c = 9/(4h^2), y = (4x_n - x_{n-1})/3 + (2h/9)(4v_n - v_{n-1});
  /// v_{n+1} = 3/(2h) (x* - (4x_n - x_{n-1})/3).
  int bdf2(double h, double t, int x_out, int v_out, const IterationControl& control);
  /// Forward Euler (symplectic = false) or symplectic Euler (true), both with f(x_n, t_n).
  void explicitEuler(double h, double t, int x_out, int v_out, bool symplectic);
  /// The integrator's step (BDF2 without history: BE), for every integrator but the blend.
  int step(Integrator integrator, double h, double t, bool has_history, int x_out, int v_out,
           const IterationControl& control);
  /// Commits the accepted step: (kXNew, kVNew) become (kX, kV); BDF2 keeps the old state as its
  /// history (kXPrev, kVPrev) and sets `has_history`.
  void commit(Integrator integrator, bool& has_history);

  /// The potential at t + h of the positions the last step left in x_out, per segment (one for a
  /// single scene), where its solve's last local step was at them (BE and BDF2 with
  /// LocalGlobalSolver::potentialsOfResult): bit for bit what an energy pass over x_out would
  /// give, without the pass. Empty after IM (x_out is then 2 x* - x_n) and the explicit steps.
  const std::vector<PotentialEnergy>& potentialsOfStep() const { return potentials_of_step_; }

 private:
  Backend& backend_;
  LocalGlobalSolver& solver_;
  std::vector<PotentialEnergy> potentials_of_step_;
};

/// `control` with its budget ending on a plain iteration (IterationControl::plain_last_iteration):
/// for the solves whose error the step carries on, implicit midpoint's and BDF2's, and the
/// blend's BE partner, which the blend combines with the IM candidate.
IterationControl endingPlain(IterationControl control);
/// `control` without the rigid motions in L-BFGS's initial Hessian (BDF2's solves, the blend's
/// backward-Euler step after a candidate that blew up).
IterationControl withoutRigidModes(IterationControl control);

/// The solver's controls for one solve of `iterations` (the budget) from the options, with the
/// energy scale the tolerance stop and the line search measure against: one place for Simulator
/// and BatchSimulator, so that a batch of one solves as its Simulator does.
IterationControl iterationControl(const SimulatorOptions& options, int iterations, double energy_scale);

/// The work the forcing does in a step (docs/method.md section 4): with p_new and p_old the
/// potentials of the new and old positions at t + h and t, and new_mid, old_mid theirs at
/// t + h/2, [U(x_1, t_1) - U(x_1, t_m)] + [U(x_0, t_m) - U(x_0, t_0)] over the pins and the
/// external terms.
double forcingWork(const PotentialEnergy& p_new, const PotentialEnergy& new_mid, const PotentialEnergy& old_mid,
                   const PotentialEnergy& p_old);

/// E_scale (docs/method.md section 7): initial K + E_int plus m |g| times the diagonal of the
/// initial bounding box, so the blend tolerance does not depend on where gravity's zero is.
double initialEnergyScale(double kinetic, const PotentialEnergy& potential, const Eigen::VectorXd& masses,
                          const Eigen::Vector3d& gravity, const Eigen::MatrixX3d& positions);

/// sum_j m_j a_j . b_j on host copies, as the CPU reference's Backend::massDot forms it.
double massDot(const Eigen::VectorXd& masses, const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b);
/// 1/2 sum_j m_j |v_j|^2 on a host copy.
double kineticEnergy(const Eigen::VectorXd& masses, const Eigen::MatrixX3d& v);

/// Why a step is refused (docs/method.md section 8). `what` says what was wrong; the message
/// names the step, its times and the integrator, as Simulator::step throws it.
struct StepRefusal {
  std::string message;        // empty: not refused
  bool energy_limit = false;  // EnergyLimitError, else NonFiniteStateError
  int step = 0;
};
StepRefusal stepRefusal(int step, double t, double t1, Integrator integrator, const std::string& what,
                        bool energy_limit);
/// The checks after a step's corrections, in Simulator::step's order: non-finite energies, then
/// the energy ceiling. Returns an empty message when the step is accepted.
StepRefusal checkStepEnergy(int step, double t, double t1, const SimulatorOptions& options, double kinetic,
                            const PotentialEnergy& potential, double target, double energy_scale);
/// The refusal of a non-finite position or velocity.
StepRefusal nonFiniteState(int step, double t, double t1, Integrator integrator);
/// A blow-up that is still finite: a position or velocity beyond validation::kMaxMagnitude, the
/// largest value setState and a checkpoint take, is refused like a non-finite one, so that every
/// accepted state can be saved, restored and set again.
StepRefusal checkStepState(int step, double t, double t1, Integrator integrator, const Eigen::MatrixX3d& x,
                           const Eigen::MatrixX3d& v);

}  // namespace stabint
