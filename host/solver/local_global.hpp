#pragma once
// Local/global iterations for one implicit solve (method.md section 2):
//   x* = argmin_x c/2 ||x - y||_M^2 + E_int(x) + U_ext(x, t).
// Each iteration projects every element at the current x (local, on the backend) and solves the
// prefactored K_c x = rhs on the host (global). The loop is shared by all backends.
#include "backend.hpp"
#include "solver/global_system.hpp"

#include <Eigen/Core>

#include <vector>

namespace stabint {

/// How long a solve runs: a fixed count (real-time budget), or with tolerance > 0 until the
/// relative change of the objective is below it (reference runs), at most max_iterations.
struct IterationControl {
  int iterations = 10;
  double tolerance = 0.0;
  int max_iterations = 1000;
  /// Energy scale the objective change is measured against (|dObj| <= tol * max(|Obj|, scale)),
  /// so that the test does not depend on where gravity's zero is.
  double energy_scale = 1.0;
};

class LocalGlobalSolver {
 public:
  /// `scratch_slot` is a backend slot the solver may overwrite.
  LocalGlobalSolver(Backend& backend, GlobalSystem& system, int scratch_slot);

  /// Runs iterations from the positions in slot `x` (the warm start) and leaves the result there.
  /// Returns the number of iterations done. When `objective_history` is given, it receives the
  /// objective at the start and after every iteration.
  int solve(double c, int y, int x, double t, const IterationControl& control,
            std::vector<double>* objective_history = nullptr);

  /// c/2 ||x - y||_M^2 + E_int(x) + U_ext(x, t)
  double objective(double c, int y, int x, double t);

 private:
  Backend& backend_;
  GlobalSystem& system_;
  int scratch_;
  Eigen::MatrixX3d rhs_, x_host_;  // reused across iterations: no per-iteration allocation
};

}  // namespace stabint
