#pragma once
// The accelerations of one implicit solve, one class each over the shared SolveContext
// (docs/method.md, "Acceleration"): plain local/global iterations, the safeguarded extrapolations
// (Chebyshev, Anderson), L-BFGS with the scene's rigid motions in its initial Hessian, and
// Newton-CG. Each keeps its own state between iterations (and, where it pays, between solves);
// in a batch every scene segment takes the steps its scene takes alone. LocalGlobalSolver picks
// one per solve from IterationControl::acceleration.
#include "solver/solve_context.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <utility>
#include <vector>

namespace stabint {

/// Plain iterations (host/solver/plain_iterations.cpp): a local and a global step each.
class PlainIterations {
 public:
  /// `taking_part`: the segments that solve (SegmentStops::begin).
  int solve(SolveContext& ctx, double c, int y, int x, double t, const IterationControl& control,
            std::vector<double>* objective_history, std::size_t taking_part);

 private:
  int solveWhole(SolveContext& ctx, double c, int y, int x, double t, const IterationControl& control,
                 std::vector<double>* objective_history);
  int solvePerSegment(SolveContext& ctx, double c, int y, int x, double t, const IterationControl& control);

  Eigen::MatrixX3d x_stopped_;  // the stopped segments' iterates
};

class Extrapolation;  // Chebyshev's or Anderson's rule (extrapolated_iterations.cpp)

/// Plain iterations with a safeguarded extrapolation, Chebyshev's or Anderson's
/// (host/solver/extrapolated_iterations.cpp).
class ExtrapolatedIterations {
 public:
  ExtrapolatedIterations();
  ~ExtrapolatedIterations();
  int solve(SolveContext& ctx, double c, int y, int x, double t, const IterationControl& control,
            std::vector<double>* objective_history);
  /// Extrapolated iterates rejected (their objective rose) since construction.
  int rejected() const { return rejected_; }

 private:
  void prepare(const IterationControl& control, std::size_t segments);
  void objectives(SolveContext& ctx, double c, int y, int x, double t, const IterationControl& control,
                  std::vector<double>& objective);
  bool propose(SolveContext& ctx, std::size_t s);

  int rejected_ = 0;
  // One rule per segment (kept with the rule's kind and constant), whether each segment's iterate
  // is extrapolated, and the rule's proposal for one segment's rows.
  std::vector<std::unique_ptr<Extrapolation>> extrapolations_;
  std::pair<bool, double> key_{false, 0.0};
  std::vector<char> extrapolated_;
  Eigen::MatrixX3d segment_next_;
};

/// L-BFGS's initial inverse Hessian with the rigid motions of each body of each segment as a
/// coarse space (host/solver/rigid_modes.cpp).
class RigidModes {
 public:
  /// At the warm start ctx.x_cur with its gradient ctx.gradient: the coarse space of every running
  /// segment flagged in `wanted` (empty: all), where control.rigid_modes and a scene allow.
  void prepare(SolveContext& ctx, double c, double t, const IterationControl& control, const std::vector<char>& wanted);
  /// r = H0 q: the two-level inverse where a segment uses its rigid motions, else K_c^-1.
  void apply(SolveContext& ctx, double c, const IterationControl& control, const Eigen::MatrixX3d& q,
             Eigen::MatrixX3d& r);
  bool on(std::size_t s) const { return !rigid_on_.empty() && rigid_on_[s]; }
  /// Segment s leaves its rigid motions for the rest of the solve.
  void drop(std::size_t s) { rigid_on_[s] = 0; }

 private:
  // The rows of each segment that move rigidly as one: its bodies where each is one run of rows,
  // else the whole segment (segment s's are units_[unit_first_[s] .. unit_first_[s + 1])). Found
  // again when the scene, its element count or the segments change.
  void findUnits(const SolveContext& ctx);

  // Per particle its arm x_i - (its unit's mass centre) at the warm start, its weight c m_i +
  // (its pins' and contacts' weights) and the other elements' energy gradient there; per unit the
  // inverse of the 6 x 6 coarse matrix and whether its coarse space is in use, per segment whether
  // any of its units' is; rigid_q_ is the two-level inverse's right-hand side.
  Eigen::MatrixX3d rigid_arms_, rigid_gradient_, rigid_q_;
  Eigen::VectorXd rigid_weights_;
  std::vector<Eigen::Matrix<double, 6, 6>> rigid_inverse_;
  std::vector<char> rigid_on_, unit_on_;
  std::vector<SegmentRows> units_;
  std::vector<std::size_t> unit_first_;
  const void* units_scene_ = nullptr;
  std::size_t units_elements_ = 0;
  std::vector<std::pair<int, int>> units_segments_;
};

/// L-BFGS with K_c^-1 (and the rigid motions) as the initial inverse Hessian
/// (host/solver/lbfgs.cpp).
class LbfgsIterations {
 public:
  /// `rigid`: the segments whose initial Hessian may take their rigid motions (empty: all).
  int solve(SolveContext& ctx, double c, int y, int x, double t, const IterationControl& control,
            std::vector<double>* objective_history, const std::vector<char>& rigid);

 private:
  void storePair(SolveContext& ctx, int slot, int stored, std::vector<double>& sy, std::vector<double>& yy,
                 std::vector<double>& ss);
  void twoLoopDirection(SolveContext& ctx, double c, const IterationControl& control, int pairs, int newest,
                        std::vector<double>& slope);
  void resetHistory(int window, std::size_t segments);
  void stopConvergedByGradient(SolveContext& ctx, int done, const IterationControl& control,
                               const std::vector<double>& slope, std::vector<double>& initial);
  void handleStayedSegments(SolveContext& ctx, int done);
  void keepCurvaturePairs(SolveContext& ctx, int slot, int done, const IterationControl& control,
                          const std::vector<double>& step, const std::vector<double>& dot,
                          const std::vector<double>& yy, const std::vector<double>& ss, std::vector<double>& objective,
                          const std::vector<double>& trial_objective);

  // The ring of curvature pairs; per ring slot and segment 1/(s.y) (0: skipped) and the two-loop's
  // coefficient; per segment the products s_i.y_j of the ring's pairs and s_i.g at x_cur.
  std::vector<Eigen::MatrixX3d> history_s_, history_y_;
  std::vector<std::vector<double>> history_rho_, history_alpha_, history_sg_;
  std::vector<Eigen::MatrixXd> gram_;
  std::vector<char> plain_direction_;  // the segment's direction used no curvature pair
  RigidModes rigid_modes_;
};

/// Newton-CG with the springs' projected Hessians (host/solver/newton.cpp).
class NewtonIterations {
 public:
  int solve(SolveContext& ctx, double c, int y, int x, double t, const IterationControl& control,
            std::vector<double>* objective_history);

 private:
  void springCurvature(SolveContext& ctx);
  void hessianTimes(SolveContext& ctx, double c, const Eigen::MatrixX3d& v, Eigen::MatrixX3d& out) const;

  // Each spring's transverse coefficient w min(1, r/|u|) and direction at the iterate, the CG
  // vectors, and per segment whether its CG goes on in this Newton step.
  struct SpringCurvature {
    int a, b;
    double beta;
    Eigen::Vector3d n;
  };
  std::vector<SpringCurvature> springs_;
  Eigen::MatrixX3d cg_z_, cg_p_, cg_hp_;
  std::vector<char> cg_running_;
};

}  // namespace stabint
