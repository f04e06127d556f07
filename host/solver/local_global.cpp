#include "solver/local_global.hpp"

#include <utility>

namespace stabint {

LocalGlobalSolver::LocalGlobalSolver(Backend& backend, GlobalSystem& system, int scratch_slot)
    : context_(backend, system, scratch_slot) {}

LocalGlobalSolver::~LocalGlobalSolver() = default;

int LocalGlobalSolver::solve(double c, int y, int x, double t, const IterationControl& control,
                             std::vector<double>* objective_history) {
  context_.resultPotentials().clear();
  // This solve's flags; the next solve's are set anew.
  std::vector<char> rigid;
  rigid.swap(next_rigid_);
  const std::size_t taking_part = context_.stops.begin(context_.rows().size(), std::move(next_solving_));
  next_solving_.clear();
  if (taking_part == 0) return 0;  // slot x stays the warm start
  // These count each segment's iterations themselves (a segment may stop before the others).
  switch (control.acceleration) {
    case Acceleration::LBFGS: return lbfgs_.solve(context_, c, y, x, t, control, objective_history, rigid);
    case Acceleration::Newton: return newton_.solve(context_, c, y, x, t, control, objective_history);
    case Acceleration::Chebyshev:
    case Acceleration::Anderson: return extrapolated_.solve(context_, c, y, x, t, control, objective_history);
    default: return plain_.solve(context_, c, y, x, t, control, objective_history, taking_part);
  }
}

}  // namespace stabint
