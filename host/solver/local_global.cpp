#include "solver/local_global.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace stabint {

LocalGlobalSolver::LocalGlobalSolver(Backend& backend, GlobalSystem& system, int scratch_slot)
    : backend_(backend), system_(system), scratch_(scratch_slot) {}

double LocalGlobalSolver::objective(double c, int y, int x, double t) {
  backend_.combine(scratch_, 1.0, x, -1.0, y);
  return 0.5 * c * backend_.massDot(scratch_, scratch_) + backend_.potential(x, t).total();
}

int LocalGlobalSolver::solve(double c, int y, int x, double t, const IterationControl& control,
                             std::vector<double>* objective_history) {
  const bool to_tolerance = control.tolerance > 0.0;
  const bool track = to_tolerance || objective_history != nullptr;
  double previous = track ? objective(c, y, x, t) : 0.0;
  if (objective_history) objective_history->assign(1, previous);

  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  int done = 0;
  while (done < limit) {
    backend_.localStepRhs(x, y, c, t, rhs_);
    const auto start = std::chrono::steady_clock::now();
    system_.solve(c, rhs_, x_host_);
    backend_.times().global += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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

}  // namespace stabint
