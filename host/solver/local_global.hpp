#pragma once
// Local/global iterations for one implicit solve (docs/method.md, "One implicit solve"):
//   x* = argmin_x c/2 ||x - y||_M^2 + E_int(x) + U_ext(x, t).
// Each iteration projects every element at the current x (local, on the backend) and solves
// K_c x = rhs (global): with the prefactored K_c on the host, or by CG (GlobalSolve::
// ConjugateGradient) on the host or, for OpenCL, on the device. The loop is shared by all backends.
#include "backend/backend.hpp"
#include "scene/scene_batch.hpp"
#include "solver/global_system.hpp"

#include <stabint/types.hpp>

#include <Eigen/Core>

#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace stabint {

class Forcing;
class SceneData;
class Extrapolation;  // Chebyshev's or Anderson's rule (local_global.cpp)

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
  double chebyshev_rho = 0.98;      // spectral radius estimate of the plain iteration
  int anderson_window = 5;          // iterates Anderson acceleration combines
  int lbfgs_history = 5;            // curvature pairs L-BFGS keeps
  double gradient_tolerance = 0.0;  // L-BFGS: stop at this fraction of the warm start's gradient
  /// L-BFGS: the last iteration of a budget is a plain one (IntegratorSteps sets it for implicit
  /// midpoint's and BDF2's solves and the blend's partner: docs/method.md, "L-BFGS").
  bool plain_last_iteration = false;
  /// L-BFGS: the initial inverse Hessian has the scene's rigid motions as a coarse space
  /// (host/solver/rigid_modes.cpp; docs/method.md, "Rigid motions in the initial Hessian").
  /// From SimulatorOptions::lbfgs_rigid_modes; IntegratorSteps clears it for BDF2's solves
  /// (withoutRigidModes), and the driver keeps it off in the implicit-midpoint and blend-partner
  /// solves of the scenes whose forcing changes (LocalGlobalSolver::setRigidModes).
  bool rigid_modes = false;
  GlobalSolve global_solve = GlobalSolve::Factor;
  int cg_iterations = 20;     // CG iterations per global step (at most, with cg_tolerance > 0)
  double cg_tolerance = 0.0;  // relative residual at which CG stops early (0: fixed count)
};

class LocalGlobalSolver {
 public:
  /// `scratch_slot` is a backend slot the solver may overwrite.
  LocalGlobalSolver(Backend& backend, GlobalSystem& system, int scratch_slot);
  ~LocalGlobalSolver();

  /// Runs iterations from the positions in slot `x` (the warm start) and leaves the result there.
  /// Returns the number of iterations (global solves) done. When `objective_history` is given,
  /// it receives the objective at the start and after every iteration. The objective never
  /// rises from one iteration to the next, with or without acceleration, and with either global
  /// solve: CG warm-started from the current iterate lowers the global step's quadratic at every
  /// CG iteration, so even an inexact global step lowers it (in exact arithmetic; to round-off
  /// of the device's precision on OpenCL; docs/method.md, "Global solve").
  int solve(double c, int y, int x, double t, const IterationControl& control,
            std::vector<double>* objective_history = nullptr);

  /// c/2 ||x - y||_M^2 + E_int(x) + U_ext(x, t)
  double objective(double c, int y, int x, double t);

  /// The potential at time t of the positions the last solve left in slot x, per segment (one for
  /// a single scene), when its last local step was at them (L-BFGS and Newton-CG, and plain
  /// solves that track their objective on one scene): equal bit for bit to Backend::potential(x,
  /// t) (a batch's: Backend::potentials), so a step takes it instead of an energy pass over the
  /// same positions. Empty otherwise.
  const std::vector<PotentialEnergy>& potentialsOfResult() const { return result_potentials_; }

  /// The iterations segment `s` took in the last solve: the solve's count, but with a stop by
  /// accuracy (any solver's tolerance, L-BFGS's gradient_tolerance) or Newton-CG's own CG counts,
  /// where each segment stops on its own, as its scene alone would, and stays there while the
  /// others go on.
  int segmentIterations(std::size_t s) const { return segment_iterations_[s]; }

  /// Accelerated iterates rejected (objective rose) since construction.
  int rejectedAccelerations() const { return rejected_; }

  /// The scenes of a batch (block-diagonal K_c): L-BFGS keeps its dot products, step lengths
  /// and history per segment, Chebyshev and Anderson their rule, objective and safeguard,
  /// Newton-CG its CG and line search, so each scene takes the steps it takes alone. Without segments
  /// the whole system is one. `energy_scales` (one per segment) replace IterationControl::
  /// energy_scale in each segment's round-off allowance.
  void setSegments(const std::vector<SceneSegment>& segments, const std::vector<double>& energy_scales);

  /// The segments the next solve solves, one flag per segment (a batch's scenes that step, or
  /// that need the blend's partner); empty: all of them. A segment not flagged keeps its rows of
  /// slot x (the warm start), takes no iteration (segmentIterations 0) and has no potential in
  /// potentialsOfResult (NaN); on the CPU reference its element passes and its trees of the
  /// factor's solve are not run, and its history work on the host is not done either way.
  /// The flags hold for the next solve only (a caller that sets none gets every segment solved).
  void setSolving(std::vector<char> segments) { next_solving_ = std::move(segments); }
  /// The segments whose L-BFGS initial Hessian may take their rigid motions in the next solve
  /// (with IterationControl::rigid_modes), one flag per segment; empty: all of them. Like
  /// setSolving, for the next solve only.
  void setRigidModes(std::vector<char> segments) { next_rigid_ = std::move(segments); }

  /// The scene whose springs Newton-CG takes its Hessians from (Acceleration::Newton) and whose
  /// one-particle elements and external forces the rigid motions read, with its forcing (both
  /// must outlive the solver); without one Newton-CG's Hessian is K_c and no solve takes the
  /// rigid motions.
  void setScene(const SceneData& scene, const Forcing& forcing);

 private:
  int solvePlain(double c, int y, int x, double t, const IterationControl& control,
                 std::vector<double>* objective_history);
  int solvePlainPerSegment(double c, int y, int x, double t, const IterationControl& control);
  // Segment s's energy scale: its scene's in a batch (setSegments), else the control's.
  double segmentScale(const IterationControl& control, std::size_t s) const {
    return segment_scales_.empty() ? control.energy_scale : segment_scales_[s];
  }
  // The stops by accuracy per segment in one solve: at the start the segments not solving
  // (setSolving) stopped after 0 iterations; segment s stopped after `done` iterations (it takes
  // no more steps); at the end the others get the solve's count.
  void startSegmentStops(std::size_t segments);
  // Whether segment s takes part in this solve (setSolving).
  bool solving(std::size_t s) const { return solving_.empty() || rows_.size() <= 1 || solving_[s] != 0; }
  // The segments still running (running_), for the passes and solves that may skip the others;
  // null while all run.
  const std::vector<char>* runningMask() const { return running_segments_ < running_.size() ? &running_ : nullptr; }
  // The potentials of the last solve's result: the segments that did not solve get NaN.
  void keepResultPotentials();
  void stopSegment(std::size_t s, int done);
  void finishSegmentStops(int done);
  int solveAccelerated(double c, int y, int x, double t, const IterationControl& control,
                       std::vector<double>* objective_history);
  void prepareExtrapolations(const IterationControl& control, std::size_t segments);
  void acceleratedObjectives(double c, int y, int x, double t, const IterationControl& control,
                             std::vector<double>& objective);
  bool proposeSegment(std::size_t s);
  // Newton-CG with the springs' projected Hessians (host/solver/newton.cpp).
  int solveNewton(double c, int y, int x, double t, const IterationControl& control,
                  std::vector<double>* objective_history);
  void springCurvature();
  void hessianTimes(double c, const Eigen::MatrixX3d& v, Eigen::MatrixX3d& out) const;
  // L-BFGS with K_c^-1 as the initial inverse Hessian (host/solver/lbfgs.cpp).
  int solveLbfgs(double c, int y, int x, double t, const IterationControl& control,
                 std::vector<double>* objective_history);
  void localStepObjectives(double c, int y, int x, double t, std::vector<double>& objective);
  void lineSearch(double c, int y, int x, double t, const IterationControl& control,
                  const std::vector<double>& objective, const std::vector<double>& slope, std::vector<double>& step,
                  std::vector<double>& trial_objective);
  void storePair(int slot, int stored, std::vector<double>& sy, std::vector<double>& yy, std::vector<double>& ss);
  void lbfgsDirection(double c, const IterationControl& control, int pairs, int newest, std::vector<double>& slope);
  void resetLbfgsHistory(int window, std::size_t segments);
  void stopConvergedByGradient(int done, const IterationControl& control, const std::vector<double>& slope,
                               std::vector<double>& initial);
  void handleStayedSegments(int done);
  void keepCurvaturePairs(int slot, int done, const IterationControl& control, const std::vector<double>& step,
                          const std::vector<double>& dot, const std::vector<double>& yy, const std::vector<double>& ss,
                          std::vector<double>& objective, const std::vector<double>& trial_objective);
  // r = K_c^-1 q (the factor's solve, or the host CG).
  void applyInitialInverseHessian(double c, const IterationControl& control, const Eigen::MatrixX3d& q,
                                  Eigen::MatrixX3d& r);
  // L-BFGS's H0: K_c^-1 with each segment's rigid motions as a coarse space where rigid_on_ says
  // so (host/solver/rigid_modes.cpp), else K_c^-1.
  void prepareRigidModes(double c, double t, const IterationControl& control);
  void applyTwoLevelInverse(double c, const IterationControl& control, const Eigen::MatrixX3d& q, Eigen::MatrixX3d& r);
  bool usesRigidModes(std::size_t s) const { return !rigid_on_.empty() && rigid_on_[s]; }
  void segmentDots(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b, std::vector<double>& out) const;
  // The global step of the iterate in slot `x`, whose local step was the last one. Factor or host
  // CG: from rhs_ into x_host_, and into slot x unless `to_host` (the caller writes slot x). On
  // the backend: into slot x, and also into x_host_ when `to_host`. The host CG starts from
  // x_host_, which the caller keeps equal to slot x.
  void globalStep(double c, int x, const IterationControl& control, bool to_host);
  // The local step at slot `x`: rhs_ on the host, or kept in the backend for its own solve.
  void localStep(double c, int y, int x, double t, const IterationControl& control, PotentialEnergy* energy);
  // The device's CG reduces over the whole system; a batch's scenes (segments) run CG on the host,
  // each on its own block (GlobalSystem::setBlocks).
  bool onBackend(const IterationControl& control) const {
    return control.global_solve == GlobalSolve::ConjugateGradient && backend_.solvesGlobalSystem() && rows_.size() <= 1;
  }
  double inertia(double c, const Eigen::MatrixX3d& x) const;
  // Segment s's rows of `m` (all of them without segments).
  auto segmentRows(Eigen::MatrixX3d& m, std::size_t s) const {
    return rows_.empty() ? m.middleRows(0, m.rows()) : m.middleRows(rows_[s].first, rows_[s].count);
  }
  // c/2 ||x - y||_M^2 over segment s's rows (y: y_host_).
  double segmentInertia(double c, const Eigen::MatrixX3d& x, std::size_t s) const;

  Backend& backend_;
  GlobalSystem& system_;
  int scratch_;
  int rejected_ = 0;
  std::vector<PotentialEnergy> result_potentials_;
  int backend_matrix_version_ = -1;  // GlobalSystem::laplacianVersion() of the backend's copy of L
  // Reused across iterations and solves: no per-iteration allocation.
  Eigen::MatrixX3d rhs_, x_host_, y_host_, x_cur_, x_next_;
  Eigen::VectorXd masses_;
  // L-BFGS: the scene segments (first particle, count), the iterate and its trial, gradients,
  // search vectors and the ring of curvature pairs.
  struct Segment {
    int first = 0;
    int count = 0;
  };
  std::vector<Segment> rows_;
  std::vector<SceneSegment> segments_;  // setSegments: each scene's element ranges (Newton's springs)
  std::vector<double> segment_scales_;
  std::vector<PotentialEnergy> segment_potentials_;
  // gradient_ is the objective's gradient at x_cur_, trial_gradient_ at the positions of the last
  // local step.
  Eigen::MatrixX3d x_trial_, gradient_, trial_gradient_, search_, direction_;
  std::vector<Eigen::MatrixX3d> history_s_, history_y_;
  // Per ring slot and segment: 1/(s.y) (0: skipped) and the two-loop's coefficient. Per segment:
  // the products s_i.y_j of the ring's pairs and s_i.g at x_cur_.
  std::vector<std::vector<double>> history_rho_, history_alpha_, history_sg_;
  std::vector<Eigen::MatrixXd> gram_;
  // L-BFGS's coarse space (rigid_modes.cpp): per particle its arm x_i - (its segment's mass
  // centre) at the warm start, its weight c m_i + (its pins' and contacts' weights) and the other
  // elements' energy gradient there; per segment the inverse of the 6 x 6 coarse matrix and
  // whether the coarse space is in use; rigid_q_ is the two-level inverse's right-hand side.
  Eigen::MatrixX3d rigid_arms_, rigid_gradient_, rigid_q_;
  Eigen::VectorXd rigid_weights_;
  std::vector<Eigen::Matrix<double, 6, 6>> rigid_inverse_;
  std::vector<char> rigid_on_;
  std::vector<double> scalars_[8];  // per-segment scalars of one solve (no allocation per solve)
  std::vector<char> accepted_, moved_;
  std::vector<char> running_;  // per segment: not stopped in this solve (the mask the passes and solves take)
  bool stopped(std::size_t s) const { return !running_[s]; }
  std::vector<char> next_solving_;        // setSolving, for the next solve
  std::vector<char> rigid_, next_rigid_;  // setRigidModes: this solve's, the next solve's
  std::vector<char> solving_;             // the solve's (next_solving_ taken at its start)
  std::vector<char> plain_direction_;     // L-BFGS: the segment's direction used no curvature pair
  std::size_t running_segments_ = 0;      // not stopped yet in this solve
  std::vector<int> segment_iterations_;   // of the last solve, per segment
  Eigen::MatrixX3d x_stopped_;            // plain iterations: the stopped segments' iterates
  // Chebyshev and Anderson: one rule per segment (kept with the rule's kind and constant), whether
  // each segment's iterate is extrapolated, and a segment's rows for its rule (and for Newton-CG's
  // dot products).
  std::vector<std::unique_ptr<Extrapolation>> extrapolations_;
  std::pair<bool, double> extrapolation_key_{false, 0.0};
  std::vector<char> extrapolated_;
  Eigen::MatrixX3d segment_x_, segment_g_, segment_next_;
  // Newton-CG: the scene, each spring's transverse coefficient w min(1, r/|u|) and direction at
  // the iterate, the CG vectors.
  const SceneData* scene_ = nullptr;
  const Forcing* forcing_ = nullptr;
  struct SpringCurvature {
    int a, b;
    double beta;
    Eigen::Vector3d n;
  };
  std::vector<SpringCurvature> springs_;
  Eigen::MatrixX3d cg_z_, cg_p_, cg_hp_;
  std::vector<char> cg_running_;  // per segment: its CG goes on in this Newton step
};

}  // namespace stabint
