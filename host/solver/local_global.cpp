#include "solver/local_global.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace stabint {

LocalGlobalSolver::LocalGlobalSolver(Backend& backend, GlobalSystem& system, int scratch_slot)
    : backend_(backend), system_(system), scratch_(scratch_slot), masses_(system.masses()) {}

double LocalGlobalSolver::objective(double c, int y, int x, double t) {
  backend_.combine(scratch_, 1.0, x, -1.0, y);
  return 0.5 * c * backend_.massDot(scratch_, scratch_) + backend_.potential(x, t).total();
}

double LocalGlobalSolver::inertia(double c, const Eigen::MatrixX3d& x) const {
  return 0.5 * c * ((x - y_host_).rowwise().squaredNorm().transpose() * masses_)(0);
}

void LocalGlobalSolver::globalSolve(double c) {
  const auto start = std::chrono::steady_clock::now();
  system_.solve(c, rhs_, x_host_);
  backend_.times().global += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int LocalGlobalSolver::solve(double c, int y, int x, double t, const IterationControl& control,
                             std::vector<double>* objective_history) {
  if (control.acceleration == Acceleration::Chebyshev)
    return solveChebyshev(c, y, x, t, control, objective_history);
  return solvePlain(c, y, x, t, control, objective_history);
}

int LocalGlobalSolver::solvePlain(double c, int y, int x, double t, const IterationControl& control,
                                  std::vector<double>* objective_history) {
  const bool to_tolerance = control.tolerance > 0.0;
  const bool track = to_tolerance || objective_history != nullptr;
  double previous = track ? objective(c, y, x, t) : 0.0;
  if (objective_history) objective_history->assign(1, previous);

  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  int done = 0;
  while (done < limit) {
    backend_.localStepRhs(x, y, c, t, rhs_);
    globalSolve(c);
    backend_.write(x, x_host_);  // the backend books its own transfer time
    ++done;
    if (!track) continue;
    const double current = objective(c, y, x, t);
    if (objective_history) objective_history->push_back(current);
    const double change = std::abs(previous - current);
    previous = current;
    if (to_tolerance && change <= control.tolerance * std::max(std::abs(current), control.energy_scale)) break;
  }
  return done;
}

// Chebyshev semi-iterative acceleration (Wang 2015): with x^ the plain local/global update of
// x_k, x_{k+1} = w_{k+1} (x^ - x_{k-1}) + x_{k-1}, w_1 = 1, w_2 = 2/(2 - rho^2),
// w_{k+1} = 4/(4 - rho^2 w_k). Safeguard: the plain update never raises the objective, the
// accelerated one may; the local step of every iterate also returns its potential, so an
// iterate whose objective rose is replaced by the plain update it was extrapolated from and the
// recurrence restarts. The last iteration is always plain, so the returned x is never worse than
// any earlier iterate.
int LocalGlobalSolver::solveChebyshev(double c, int y, int x, double t, const IterationControl& control,
                                      std::vector<double>* objective_history) {
  const bool to_tolerance = control.tolerance > 0.0;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  const double rho2 = control.chebyshev_rho * control.chebyshev_rho;
  backend_.read(y, y_host_);
  backend_.read(x, x_cur_);
  x_prev_ = x_cur_;
  if (objective_history) objective_history->clear();

  double accepted_objective = 0.0;  // objective of the last accepted iterate
  bool have_accepted = false;
  bool extrapolated = false;        // x_cur_ is an accelerated (not plain) iterate
  int chebyshev_step = 0;           // k of the recurrence since its last (re)start
  double omega = 1.0;
  int done = 0;
  PotentialEnergy potential;
  while (true) {
    backend_.localStepRhs(x, y, c, t, rhs_, &potential);
    double current = inertia(c, x_cur_) + potential.total();
    // A rise within round-off of the objective is no rise: deciding on noise would make two
    // backends that agree to round-off take different iterates.
    const double noise = 1e-12 * std::max(std::abs(accepted_objective), control.energy_scale);
    if (extrapolated && have_accepted && !(current <= accepted_objective + noise)) {
      // Reject: fall back to the plain update (in x_host_) from x_prev_, restart the recurrence.
      ++rejected_;
      x_cur_ = x_host_;
      backend_.write(x, x_cur_);
      backend_.localStepRhs(x, y, c, t, rhs_, &potential);
      current = inertia(c, x_cur_) + potential.total();
      chebyshev_step = 1;
    }
    if (objective_history) objective_history->push_back(current);
    const bool converged =
        to_tolerance && have_accepted &&
        std::abs(accepted_objective - current) <= control.tolerance * std::max(std::abs(current), control.energy_scale);
    accepted_objective = current;
    have_accepted = true;
    if (done >= limit || converged) break;

    globalSolve(c);  // x_host_ = plain update of x_cur_
    ++done;
    ++chebyshev_step;
    omega = chebyshev_step == 1 ? 1.0 : chebyshev_step == 2 ? 2.0 / (2.0 - rho2) : 4.0 / (4.0 - rho2 * omega);
    const bool last = done >= limit;
    if (last || omega == 1.0) {
      x_prev_.swap(x_cur_);
      x_cur_ = x_host_;
      extrapolated = false;
    } else {
      // x_next = omega (x^ - x_prev) + x_prev, written into x_prev_ then swapped in.
      x_prev_ = omega * (x_host_ - x_prev_) + x_prev_;
      x_prev_.swap(x_cur_);
      extrapolated = true;
    }
    backend_.write(x, x_cur_);
    if (last && !objective_history) break;  // the final plain iterate needs no local step
  }
  return done;
}

}  // namespace stabint
