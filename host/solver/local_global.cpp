#include "solver/local_global.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

#include <Eigen/Dense>

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

void LocalGlobalSolver::localStep(double c, int y, int x, double t, const IterationControl& control,
                                  PotentialEnergy* energy) {
  if (onBackend(control)) {
    backend_.localStep(x, y, c, t, energy);
  } else {
    backend_.localStepRhs(x, y, c, t, rhs_, energy);
  }
}

void LocalGlobalSolver::globalStep(double c, int x, const IterationControl& control, bool to_host) {
  const auto start = std::chrono::steady_clock::now();
  if (onBackend(control)) {
    // The backend's copy of L follows every change of L (grabs, element changes) here, before
    // the first solve that needs it.
    if (backend_matrix_version_ != system_.laplacianVersion()) {
      backend_.setGlobalMatrix(system_.stiffnessLaplacian());
      backend_matrix_version_ = system_.laplacianVersion();
    }
    backend_.solveGlobal(c, x, control.cg_iterations, control.cg_tolerance);
    backend_.times().global += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (to_host) backend_.read(x, x_host_);
    return;
  }
  if (control.global_solve == GlobalSolve::ConjugateGradient) {
    system_.solveConjugateGradient(c, rhs_, x_host_, control.cg_iterations, control.cg_tolerance, runningMask());
  } else {
    system_.solve(c, rhs_, x_host_, runningMask());
  }
  backend_.times().global += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!to_host) backend_.write(x, x_host_);  // the backend books its own transfer time
}

int LocalGlobalSolver::solve(double c, int y, int x, double t, const IterationControl& control,
                             std::vector<double>* objective_history) {
  result_potentials_.clear();
  solving_.swap(next_solving_);  // this solve's flags; the next solve's are set anew
  next_solving_.clear();
  rigid_.swap(next_rigid_);
  next_rigid_.clear();
  running_.clear();  // no stops yet: every pass and solve over the whole batch
  running_segments_ = 0;
  const std::size_t segments = std::max<std::size_t>(1, rows_.size());
  std::size_t taking_part = 0;
  for (std::size_t s = 0; s < segments; ++s) taking_part += solving(s) ? 1 : 0;
  if (taking_part == 0) {  // slot x stays the warm start
    segment_iterations_.assign(segments, 0);
    return 0;
  }
  // These count each segment's iterations themselves (a segment may stop before the others).
  if (control.acceleration == Acceleration::LBFGS) return solveLbfgs(c, y, x, t, control, objective_history);
  if (control.acceleration == Acceleration::Newton) return solveNewton(c, y, x, t, control, objective_history);
  if (control.acceleration == Acceleration::Chebyshev || control.acceleration == Acceleration::Anderson)
    return solveAccelerated(c, y, x, t, control, objective_history);
  if ((control.tolerance > 0.0 || taking_part < segments) && rows_.size() > 1)
    return solvePlainPerSegment(c, y, x, t, control);
  const int done = solvePlain(c, y, x, t, control, objective_history);
  segment_iterations_.assign(std::max<std::size_t>(1, rows_.size()), done);
  return done;
}

void LocalGlobalSolver::startSegmentStops(std::size_t segments) {
  running_.assign(segments, 1);
  segment_iterations_.assign(segments, 0);
  running_segments_ = segments;
  for (std::size_t s = 0; s < segments; ++s)
    if (!solving(s)) stopSegment(s, 0);
}

void LocalGlobalSolver::stopSegment(std::size_t s, int done) {
  running_[s] = 0;
  segment_iterations_[s] = done;
  --running_segments_;
}

void LocalGlobalSolver::keepResultPotentials() {
  result_potentials_ = segment_potentials_;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t s = 0; s < result_potentials_.size(); ++s)
    if (!solving(s)) result_potentials_[s] = PotentialEnergy{nan, nan, nan};
}

void LocalGlobalSolver::finishSegmentStops(int done) {
  for (std::size_t s = 0; s < running_.size(); ++s)
    if (running_[s]) segment_iterations_[s] = done;
}

int LocalGlobalSolver::solvePlain(double c, int y, int x, double t, const IterationControl& control,
                                  std::vector<double>* objective_history) {
  const bool to_tolerance = control.tolerance > 0.0;
  const bool track = to_tolerance || objective_history != nullptr;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  if (control.global_solve == GlobalSolve::ConjugateGradient && !onBackend(control)) backend_.read(x, x_host_);
  if (!track) {
    for (int done = 0; done < limit; ++done) {
      localStep(c, y, x, t, control, nullptr);
      globalStep(c, x, control, /*to_host=*/false);
    }
    // On the backend the iterations were only queued: wait here, once per solve, so that the
    // phase times (and a benchmark) see them done. Booked as global: local steps, gathers and CG
    // run back to back on the device without a wait between them.
    if (onBackend(control)) {
      const auto start = std::chrono::steady_clock::now();
      backend_.synchronize();
      backend_.times().global += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return std::max(limit, 0);
  }
  // The objective of each iterate comes from the local step at it, whose element pass also
  // returns the potential (equal to potential() bit for bit): one pass per iterate instead of an
  // energy pass and a local step with the same projections. The pass after the last iterate only
  // serves its objective.
  PotentialEnergy potential;
  auto localStepAndObjective = [&] {
    localStep(c, y, x, t, control, &potential);
    if (rows_.size() <= 1) result_potentials_.assign(1, potential);  // a batch's is their sum
    backend_.combine(scratch_, 1.0, x, -1.0, y);
    return 0.5 * c * backend_.massDot(scratch_, scratch_) + potential.total();
  };
  double previous = localStepAndObjective();
  if (objective_history) objective_history->assign(1, previous);
  int done = 0;
  while (done < limit) {
    globalStep(c, x, control, /*to_host=*/false);
    ++done;
    const double current = localStepAndObjective();
    if (objective_history) objective_history->push_back(current);
    const double change = std::abs(previous - current);
    previous = current;
    if (to_tolerance && change <= control.tolerance * std::max(std::abs(current), control.energy_scale)) break;
  }
  return done;
}

// Plain iterations of a batch with the tolerance stop, or of some of its scenes (setSolving): each
// segment's objective is its scene's (the local step's per-scene energies and massDots: the
// numbers its own Simulator's solve computes) and so is its stop; a segment that has stopped, or
// takes no part, keeps its iterate (its rows are written back after every later global step) and
// the count at its stop, while the others go on. The local step at each iterate gives both its
// objectives and the next global step's right-hand side: one element pass per iteration.
int LocalGlobalSolver::solvePlainPerSegment(double c, int y, int x, double t, const IterationControl& control) {
  const std::size_t segments = rows_.size();
  const bool to_tolerance = control.tolerance > 0.0;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  std::vector<double>&previous = scalars_[0], &current = scalars_[1], &dots = scalars_[2];
  auto objectives = [&](std::vector<double>& out) {
    backend_.localStepRhsPerScene(x, y, c, t, rhs_, segment_potentials_, runningMask());
    backend_.combine(scratch_, 1.0, x, -1.0, y);
    backend_.massDots(scratch_, scratch_, dots);
    out.resize(segments);
    for (std::size_t s = 0; s < segments; ++s) out[s] = 0.5 * c * dots[s] + segment_potentials_[s].total();
  };
  startSegmentStops(segments);
  // The warm start: CG's, and the rows of the segments that take no part.
  if (control.global_solve == GlobalSolve::ConjugateGradient || running_segments_ < segments) backend_.read(x, x_host_);
  if (running_segments_ < segments) x_stopped_ = x_host_;
  objectives(previous);
  int done = 0;
  while (done < limit) {
    globalStep(c, x, control, /*to_host=*/true);
    ++done;
    for (std::size_t s = 0; s < segments && running_segments_ < segments; ++s)
      if (stopped(s))
        x_host_.middleRows(rows_[s].first, rows_[s].count) = x_stopped_.middleRows(rows_[s].first, rows_[s].count);
    backend_.write(x, x_host_);
    objectives(current);
    for (std::size_t s = 0; s < segments; ++s) {
      if (stopped(s)) continue;
      const double scale = segmentScale(control, s);
      if (to_tolerance &&
          std::abs(previous[s] - current[s]) <= control.tolerance * std::max(std::abs(current[s]), scale)) {
        stopSegment(s, done);
        if (x_stopped_.rows() != x_host_.rows()) x_stopped_.resize(x_host_.rows(), 3);
        x_stopped_.middleRows(rows_[s].first, rows_[s].count) = x_host_.middleRows(rows_[s].first, rows_[s].count);
      }
    }
    previous.swap(current);
    if (running_segments_ == 0) break;
  }
  finishSegmentStops(done);
  keepResultPotentials();  // of slot x as it is left
  return done;
}

// The extrapolation rules of the safeguarded loop below. Given the accepted iterate x_k and its
// plain update g = G(x_k), propose() writes x_{k+1} and returns true, or returns false to take
// g itself. start() begins a solve; rejected() follows an x_{k+1} whose objective rose (the loop
// then continues from g, the plain update of the accepted x_k). A batch keeps one per scene.
class Extrapolation {
 public:
  virtual ~Extrapolation() = default;
  virtual void start() = 0;
  virtual void rejected() = 0;
  virtual bool propose(const Eigen::MatrixX3d& x_k, const Eigen::MatrixX3d& g, Eigen::MatrixX3d& next) = 0;
};

namespace {

// Chebyshev semi-iteration (Wang 2015): x_{k+1} = w_{k+1} (g - x_{k-1}) + x_{k-1}, w_1 = 1,
// w_2 = 2/(2 - rho^2), w_{k+1} = 4/(4 - rho^2 w_k).
class Chebyshev final : public Extrapolation {
 public:
  explicit Chebyshev(double rho) : rho2_(rho * rho) {}
  void start() override { step_ = 0; }
  void rejected() override { step_ = 1; }  // x_prev_ is the accepted x_k: w_2 comes next
  bool propose(const Eigen::MatrixX3d& x_k, const Eigen::MatrixX3d& g, Eigen::MatrixX3d& next) override {
    ++step_;
    omega_ = step_ == 1 ? 1.0 : step_ == 2 ? 2.0 / (2.0 - rho2_) : 4.0 / (4.0 - rho2_ * omega_);
    const bool extrapolate = step_ > 1;
    if (extrapolate) next = omega_ * (g - x_prev_) + x_prev_;
    x_prev_ = x_k;
    return extrapolate;
  }

 private:
  double rho2_;
  int step_ = 0;
  double omega_ = 1.0;
  Eigen::MatrixX3d x_prev_;
};

// Anderson acceleration (type II, as in Peng et al. 2018) over the last `window` iterates:
// with residuals f_i = g_i - x_i, theta = argmin ||f_k - dF theta|| over the differences of
// consecutive residuals, x_{k+1} = g_k - dG theta.
class Anderson final : public Extrapolation {
 public:
  explicit Anderson(int window) : window_(window) {}
  void start() override { clear(); }
  void rejected() override { clear(); }
  bool propose(const Eigen::MatrixX3d& x_k, const Eigen::MatrixX3d& g, Eigen::MatrixX3d& next) override {
    const Eigen::Index size = g.size();
    const Eigen::VectorXd g_flat = Eigen::Map<const Eigen::VectorXd>(g.data(), size);
    const Eigen::VectorXd f = g_flat - Eigen::Map<const Eigen::VectorXd>(x_k.data(), size);
    if (have_previous_) {
      if (d_f_.rows() != size) d_f_.resize(size, window_), d_g_.resize(size, window_);
      const int column = count_ % window_;
      d_f_.col(column) = f - f_prev_;
      d_g_.col(column) = g_flat - g_prev_;
      ++count_;
    }
    f_prev_ = f;
    g_prev_ = g_flat;
    have_previous_ = true;
    const int used = std::min(count_, window_);
    if (used == 0) return false;
    const Eigen::VectorXd theta = d_f_.leftCols(used).colPivHouseholderQr().solve(f);
    if (!theta.allFinite()) return false;
    next = g;
    Eigen::Map<Eigen::VectorXd>(next.data(), size) -= d_g_.leftCols(used) * theta;
    return true;
  }

 private:
  void clear() {
    count_ = 0;
    have_previous_ = false;
  }
  int window_;
  int count_ = 0;  // differences stored so far (the last `window_` are kept)
  bool have_previous_ = false;
  Eigen::VectorXd f_prev_, g_prev_;
  Eigen::MatrixXd d_f_, d_g_;
};

}  // namespace

LocalGlobalSolver::~LocalGlobalSolver() = default;

double LocalGlobalSolver::segmentInertia(double c, const Eigen::MatrixX3d& x, std::size_t s) const {
  const Segment& seg = rows_[s];
  const auto d = x.middleRows(seg.first, seg.count) - y_host_.middleRows(seg.first, seg.count);
  return 0.5 * c * (d.rowwise().squaredNorm().transpose() * masses_.segment(seg.first, seg.count))(0);
}

// One rule per segment, kept from one solve to the next (their vectors are reused): new ones only
// when the rule, its constant or the segments change.
void LocalGlobalSolver::prepareExtrapolations(const IterationControl& control, std::size_t segments) {
  const bool anderson = control.acceleration == Acceleration::Anderson;
  const double constant = anderson ? control.anderson_window : control.chebyshev_rho;
  if (extrapolations_.size() == segments && extrapolation_key_ == std::make_pair(anderson, constant)) return;
  extrapolations_.clear();
  for (std::size_t s = 0; s < segments; ++s) {
    if (anderson)
      extrapolations_.push_back(std::make_unique<Anderson>(control.anderson_window));
    else
      extrapolations_.push_back(std::make_unique<Chebyshev>(control.chebyshev_rho));
  }
  extrapolation_key_ = {anderson, constant};
}

// The local step at slot x (= x_cur_) and every segment's objective there. One segment: the whole
// scene's pass and inertia, as a Simulator has always computed them.
void LocalGlobalSolver::acceleratedObjectives(double c, int y, int x, double t, const IterationControl& control,
                                              std::vector<double>& objective) {
  if (rows_.size() <= 1) {
    PotentialEnergy potential;
    localStep(c, y, x, t, control, &potential);
    objective.assign(1, inertia(c, x_cur_) + potential.total());
    return;
  }
  backend_.localStepRhsPerScene(x, y, c, t, rhs_, segment_potentials_, runningMask());
  objective.resize(rows_.size());
  for (std::size_t s = 0; s < rows_.size(); ++s)
    objective[s] = segmentInertia(c, x_cur_, s) + segment_potentials_[s].total();
}

// Segment s's extrapolation from its rows of x_cur_ (x_k) and x_host_ (g) into x_next_. One
// segment works on the whole matrices; a batch's segments on copies of their rows, so that each
// rule sees the vectors its scene alone has.
bool LocalGlobalSolver::proposeSegment(std::size_t s) {
  Extrapolation& rule = *extrapolations_[s];
  if (rows_.size() <= 1) return rule.propose(x_cur_, x_host_, x_next_);
  const Segment& seg = rows_[s];
  segment_x_ = x_cur_.middleRows(seg.first, seg.count);
  segment_g_ = x_host_.middleRows(seg.first, seg.count);
  const bool extrapolated = rule.propose(segment_x_, segment_g_, segment_next_);
  if (extrapolated) x_next_.middleRows(seg.first, seg.count) = segment_next_;
  return extrapolated;
}

// Safeguarded acceleration: the plain update never raises the objective, an extrapolated one
// may. The local step of every iterate also returns its potential, so an iterate whose
// objective rose is replaced by the plain update of the last accepted iterate and the
// extrapolation restarts. The last iteration is always plain, so the returned x is never worse
// than any earlier iterate. In a batch every segment has its own rule, objective, rejections and
// tolerance stop (a stopped segment keeps its iterate while the others go on), so a scene takes
// the iterates it takes alone.
int LocalGlobalSolver::solveAccelerated(double c, int y, int x, double t, const IterationControl& control,
                                        std::vector<double>* objective_history) {
  const std::size_t segments = std::max<std::size_t>(1, rows_.size());
  prepareExtrapolations(control, segments);
  const bool to_tolerance = control.tolerance > 0.0;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  backend_.read(y, y_host_);
  backend_.read(x, x_cur_);
  if (x_next_.rows() != x_cur_.rows()) x_next_.resize(x_cur_.rows(), 3);
  if (objective_history) objective_history->clear();
  for (auto& rule : extrapolations_) rule->start();
  startSegmentStops(segments);

  std::vector<double>&accepted_objective = scalars_[0], &current = scalars_[1];  // of the last accepted iterate
  accepted_objective.assign(segments, 0.0);
  bool have_accepted = false;
  extrapolated_.assign(segments, 0);  // x_cur_'s rows of the segment are extrapolated (not plain)
  int done = 0;
  while (true) {
    acceleratedObjectives(c, y, x, t, control, current);
    bool rejected = false;
    for (std::size_t s = 0; s < segments; ++s) {
      if (stopped(s)) continue;
      // A rise within round-off of the objective is no rise: deciding on noise would make two
      // backends that agree to round-off take different iterates.
      const double noise = 1e-12 * std::max(std::abs(accepted_objective[s]), segmentScale(control, s));
      if (extrapolated_[s] && have_accepted && !(current[s] <= accepted_objective[s] + noise)) {
        ++rejected_;
        rejected = true;
        segmentRows(x_cur_, s) = segmentRows(x_host_, s);  // the plain update of the last accepted iterate
        extrapolations_[s]->rejected();
      }
    }
    if (rejected) {
      backend_.write(x, x_cur_);
      acceleratedObjectives(c, y, x, t, control, current);
    }
    if (objective_history) objective_history->push_back(current[0]);
    for (std::size_t s = 0; s < segments; ++s) {
      if (stopped(s)) continue;
      const bool converged = to_tolerance && have_accepted &&
                             std::abs(accepted_objective[s] - current[s]) <=
                                 control.tolerance * std::max(std::abs(current[s]), segmentScale(control, s));
      accepted_objective[s] = current[s];
      if (converged) stopSegment(s, done);
    }
    have_accepted = true;
    if (done >= limit || running_segments_ == 0) break;

    // x_host_ = the plain update of x_cur_ (which the host CG also starts from).
    if (control.global_solve == GlobalSolve::ConjugateGradient) x_host_ = x_cur_;
    globalStep(c, x, control, /*to_host=*/true);
    ++done;
    const bool last = done >= limit;
    for (std::size_t s = 0; s < segments; ++s) {
      if (stopped(s)) continue;  // its rows of x_cur_ stay at its last iterate
      extrapolated_[s] = proposeSegment(s) && !last;
      segmentRows(x_cur_, s) = extrapolated_[s] ? segmentRows(x_next_, s) : segmentRows(x_host_, s);
    }
    backend_.write(x, x_cur_);
    if (last && !objective_history) break;  // the final plain iterate needs no local step
  }
  finishSegmentStops(done);
  return done;
}

}  // namespace stabint
