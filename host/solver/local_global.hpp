#pragma once
// Local/global iterations for one implicit solve (docs/method.md, "One implicit solve"):
//   x* = argmin_x c/2 ||x - y||_M^2 + E_int(x) + U_ext(x, t).
// Each iteration projects every element at the current x (local, on the backend) and solves the
// prefactored K_c x = rhs on the host (global). The loop is shared by all backends.
#include "backend.hpp"
#include "solver/global_system.hpp"

#include <stabint/simulator.hpp>

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
  Acceleration acceleration = Acceleration::None;
  double chebyshev_rho = 0.98;  // spectral radius estimate of the plain iteration
  int anderson_window = 5;      // iterates Anderson acceleration combines
};

class LocalGlobalSolver {
 public:
  /// `scratch_slot` is a backend slot the solver may overwrite.
  LocalGlobalSolver(Backend& backend, GlobalSystem& system, int scratch_slot);

  /// Runs iterations from the positions in slot `x` (the warm start) and leaves the result there.
  /// Returns the number of iterations (global solves) done. When `objective_history` is given,
  /// it receives the objective at the start and after every iteration. The objective never
  /// rises from one iteration to the next, with or without acceleration.
  int solve(double c, int y, int x, double t, const IterationControl& control,
            std::vector<double>* objective_history = nullptr);

  /// c/2 ||x - y||_M^2 + E_int(x) + U_ext(x, t)
  double objective(double c, int y, int x, double t);

  /// Accelerated iterates rejected (objective rose) since construction.
  int rejectedAccelerations() const { return rejected_; }

 private:
  int solvePlain(double c, int y, int x, double t, const IterationControl& control,
                 std::vector<double>* objective_history);
  int solveAccelerated(double c, int y, int x, double t, const IterationControl& control,
                       std::vector<double>* objective_history);
  void globalSolve(double c);
  double inertia(double c, const Eigen::MatrixX3d& x) const;

  Backend& backend_;
  GlobalSystem& system_;
  int scratch_;
  int rejected_ = 0;
  // Reused across iterations and solves: no per-iteration allocation.
  Eigen::MatrixX3d rhs_, x_host_, y_host_, x_cur_, x_next_;
  Eigen::VectorXd masses_;
};

}  // namespace stabint
