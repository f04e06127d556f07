#pragma once
// What every acceleration of one implicit solve shares (docs/method.md, "Local/global iterations"):
// the backend and the prefactored system, the local and global steps, the scene segments of a
// batch with their stops, and the host copies of the iterates. LocalGlobalSolver owns one and
// hands it to the acceleration a solve runs (host/solver/accelerations.hpp).
#include "backend/backend.hpp"
#include "scene/scene_batch.hpp"
#include "solver/global_system.hpp"

#include <stabint/types.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <vector>

namespace stabint {

class Forcing;
class SceneData;

/// The fields of SimulatorOptions (include/stabint/options_table.h) that a solve reads, by name:
/// IterationControl takes each one's type and default from SimulatorOptions, and
/// iterationControl (host/integrator/integrator_steps.cpp) copies them.
// clang-format off
#define STABINT_SOLVER_OPTION_NAMES(X) \
  X(iterations) X(tolerance) X(max_iterations) X(acceleration) X(chebyshev_rho) X(anderson_window) \
  X(lbfgs_history) X(gradient_tolerance) X(global_solve) X(cg_iterations) X(cg_tolerance)
// clang-format on

/// How long a solve runs and how it iterates: the solver's options (their meaning is their rows'),
/// with `iterations` the step's budget, and the controls the integrators set per solve. A fixed
/// count runs `iterations` (the real-time budget); with tolerance > 0 the solve runs until the
/// relative change of the objective is below it (reference runs), at most max_iterations.
struct IterationControl {
#define STABINT_SOLVER_OPTION_FIELD_(name) decltype(SimulatorOptions::name) name = SimulatorOptions{}.name;
  STABINT_SOLVER_OPTION_NAMES(STABINT_SOLVER_OPTION_FIELD_)
#undef STABINT_SOLVER_OPTION_FIELD_
  /// Energy scale the objective change is measured against (|dObj| <= tol * max(|Obj|, scale)),
  /// so that the test does not depend on where gravity's zero is.
  double energy_scale = 1.0;
  /// L-BFGS: the last iteration of a budget is a plain one (IntegratorSteps sets it for implicit
  /// midpoint's and BDF2's solves and the blend's partner: docs/method.md, "L-BFGS").
  bool plain_last_iteration = false;
  /// L-BFGS: the initial inverse Hessian has the scene's rigid motions as a coarse space
  /// (host/solver/rigid_modes.cpp; docs/method.md, "Rigid motions in the initial Hessian").
  /// From SimulatorOptions::lbfgs_rigid_modes; IntegratorSteps clears it for BDF2's solves
  /// (withoutRigidModes), and the driver keeps it off in the implicit-midpoint and blend-partner
  /// solves of the scenes whose forcing changes (LocalGlobalSolver::setRigidModes).
  bool rigid_modes = false;

  /// `count` plain iterations (no acceleration), every other field at its option's default.
  static IterationControl plain(int count) {
    IterationControl control;
    control.iterations = control.max_iterations = count;
    control.acceleration = Acceleration::None;
    return control;
  }
};

/// One scene's particle rows of the system: first particle and count.
struct SegmentRows {
  int first = 0;
  int count = 0;
};

/// Which segments of a batch still run in one solve, and the iterations each took: a segment
/// stops on its own (its accuracy stop, or no part in the solve), as its scene alone would, and
/// stays there while the others go on.
class SegmentStops {
 public:
  /// Starts a solve of `segments` segments (0: the whole system, before any has rows) of which
  /// those flagged in `flags` take part (empty: all); no stops yet. Returns how many take part.
  std::size_t begin(std::size_t segments, std::vector<char> flags);
  /// Whether segment s takes part in this solve.
  bool solving(std::size_t s) const { return solving_.empty() || whole_ || solving_[s] != 0; }
  /// Tracks stops over `segments` segments: those not solving stop after 0 iterations.
  void start(std::size_t segments);
  /// Segment s stops after `done` iterations: it takes no more steps.
  void stop(std::size_t s, int done);
  /// The segments still running get the solve's count.
  void finish(int done);
  bool stopped(std::size_t s) const { return !running_[s]; }
  std::size_t runningCount() const { return running_count_; }
  const std::vector<char>& running() const { return running_; }
  /// The segments still running, for the passes and solves that may skip the others; null while
  /// all run.
  const std::vector<char>* mask() const { return running_count_ < running_.size() ? &running_ : nullptr; }
  /// Each segment's iterations in the last solve (LocalGlobalSolver::segmentIterations).
  std::vector<int>& iterations() { return iterations_; }
  const std::vector<int>& iterations() const { return iterations_; }

 private:
  bool whole_ = true;              // one segment: every flag is moot
  std::vector<char> solving_;      // this solve's flags
  std::vector<char> running_;      // per segment: not stopped in this solve
  std::size_t running_count_ = 0;  // not stopped yet in this solve
  std::vector<int> iterations_;    // of the last solve, per segment
};

class SolveContext {
 public:
  /// `scratch_slot` is a backend slot the solve may overwrite.
  SolveContext(Backend& backend, GlobalSystem& system, int scratch_slot);

  Backend& backend() const { return backend_; }
  GlobalSystem& system() const { return system_; }
  int scratch() const { return scratch_; }

  /// The scenes of a batch (block-diagonal K_c) and each one's energy scale (LocalGlobalSolver::
  /// setSegments); without them the whole system is one segment.
  void setSegments(const std::vector<SceneSegment>& segments, const std::vector<double>& energy_scales);
  const std::vector<SceneSegment>& sceneSegments() const { return segments_; }
  /// Each segment's rows; empty until setSegments or coverWholeSystem.
  const std::vector<SegmentRows>& rows() const { return rows_; }
  /// Makes the whole system one segment where no setSegments gave any (the accelerations that
  /// keep per-segment state).
  void coverWholeSystem();
  /// The scene Newton-CG's springs and the rigid motions read, with its forcing; null until set.
  void setScene(const SceneData& scene, const Forcing& forcing);
  const SceneData* scene() const { return scene_; }
  const Forcing* forcing() const { return forcing_; }

  /// The contact set's changes within a solve (docs/method.md, "Contact", "Leaving within the
  /// solve"): called with the slot of the iterate, the forces on its particles there less the
  /// inertia's (elastic, pins, external and contact: the objective's gradient less c M (x - y),
  /// negated), the solve's time, the flags of the segments still running, and `release` (true:
  /// pairs the iterate and those forces carry away from their colliders leave; false: pairs that
  /// left and whose particles are inside again return). It changes the set, and K_c with it, and
  /// returns one flag per segment whose set changed (empty: none).
  using ContactChange = std::function<std::vector<char>(int x, const Eigen::MatrixX3d& forces, double t,
                                                        const std::vector<char>& running, bool release)>;
  void setContactChange(ContactChange change) { contact_change_ = std::move(change); }
  /// After iteration `done` of a solve (coefficient c) of at most `limit` with the iterate in slot
  /// x at time t (x_cur, its gradient in `gradient`; `search` is overwritten),
  /// when iterations follow: the release after the third (kReleaseIteration), the returns after
  /// each later one. The flags of the segments whose set changed; empty where none did.
  std::vector<char> changeContacts(double c, int done, int limit, int x, double t, bool& release);

  /// Segment s's energy scale: its scene's in a batch, else the control's.
  double segmentScale(const IterationControl& control, std::size_t s) const {
    return segment_scales_.empty() ? control.energy_scale : segment_scales_[s];
  }

  /// The potentials of the last solve's result per segment (LocalGlobalSolver::
  /// potentialsOfResult); keepResultPotentials takes segment_potentials, NaN where a segment did
  /// not solve.
  std::vector<PotentialEnergy>& resultPotentials() { return result_potentials_; }
  const std::vector<PotentialEnergy>& resultPotentials() const { return result_potentials_; }
  void keepResultPotentials();

  /// c/2 ||x - y||_M^2 + E_int(x) + U_ext(x, t) of slots y and x.
  double objective(double c, int y, int x, double t);
  /// c/2 ||x - y_host||_M^2, over the whole system or segment s's rows.
  double inertia(double c, const Eigen::MatrixX3d& x) const;
  double segmentInertia(double c, const Eigen::MatrixX3d& x, std::size_t s) const;
  /// Segment s's rows of `m` (all of them without segments).
  auto segmentRows(Eigen::MatrixX3d& m, std::size_t s) const {
    return rows_.empty() ? m.middleRows(0, m.rows()) : m.middleRows(rows_[s].first, rows_[s].count);
  }
  /// a.b over each segment's rows.
  void segmentDots(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b, std::vector<double>& out) const;

  /// The device's CG reduces over the whole system; a batch's scenes run CG on the host, each on
  /// its own block (GlobalSystem::setBlocks).
  bool onBackend(const IterationControl& control) const {
    return control.global_solve == GlobalSolve::ConjugateGradient && backend_.solvesGlobalSystem() && rows_.size() <= 1;
  }
  /// The local step at slot `x`: rhs on the host, or kept in the backend for its own solve.
  void localStep(double c, int y, int x, double t, const IterationControl& control, PotentialEnergy* energy);
  /// The global step of the iterate in slot `x`, whose local step was the last one. Factor or host
  /// CG: from rhs into x_host, and into slot x unless `to_host` (the caller writes slot x). On
  /// the backend: into slot x, and also into x_host when `to_host`. The host CG starts from
  /// x_host, which the caller keeps equal to slot x.
  void globalStep(double c, int x, const IterationControl& control, bool to_host);
  /// r = K_c^-1 q (the factor's solve, or the host CG).
  void applyInitialInverseHessian(double c, const IterationControl& control, const Eigen::MatrixX3d& q,
                                  Eigen::MatrixX3d& r);
  /// The objective of every segment at the positions x_trial (already in slot x), from the local
  /// step that also leaves the gradient there in trial_gradient.
  void localStepObjectives(double c, int y, int x, double t, std::vector<double>& objective);
  /// The backtracking line search of L-BFGS and Newton-CG from x_cur along `direction`
  /// (solve_context.cpp); moved() flags the segments that moved.
  void lineSearch(double c, int y, int x, double t, const IterationControl& control,
                  const std::vector<double>& objective, const std::vector<double>& slope, std::vector<double>& step,
                  std::vector<double>& trial_objective);
  const std::vector<char>& moved() const { return moved_; }

  // The host copies the accelerations iterate on, reused across iterations and solves (no
  // allocation per iteration): the masses; the global step's right-hand side and result; y; the
  // accepted iterate, the next and a trial one; the objective's gradient at x_cur and at the
  // positions of the last local step (trial_gradient); a search vector and a direction; copies of
  // one segment's rows; per-segment scalars of one solve; the segments' potentials of the last
  // per-scene pass.
  Eigen::VectorXd masses;
  Eigen::MatrixX3d rhs, x_host, y_host, x_cur, x_next, x_trial, gradient, trial_gradient, search, direction;
  Eigen::MatrixX3d segment_x, segment_g;
  std::vector<double> scalars[8];
  std::vector<PotentialEnergy> segment_potentials;
  SegmentStops stops;

 private:
  Backend& backend_;
  GlobalSystem& system_;
  int scratch_;
  int backend_matrix_version_ = -1;  // GlobalSystem::laplacianVersion() of the backend's copy of L
  std::vector<SegmentRows> rows_;
  std::vector<SceneSegment> segments_;  // setSegments: each scene's element ranges (Newton's springs)
  std::vector<double> segment_scales_;
  std::vector<PotentialEnergy> result_potentials_;
  std::vector<char> accepted_, moved_;  // lineSearch's, per segment
  const SceneData* scene_ = nullptr;
  const Forcing* forcing_ = nullptr;
  ContactChange contact_change_;
};

}  // namespace stabint
