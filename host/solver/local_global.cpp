#include "solver/local_global.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

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
    system_.solveConjugateGradient(c, rhs_, x_host_, control.cg_iterations, control.cg_tolerance);
  } else {
    system_.solve(c, rhs_, x_host_);
  }
  backend_.times().global += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!to_host) backend_.write(x, x_host_);  // the backend books its own transfer time
}

int LocalGlobalSolver::solve(double c, int y, int x, double t, const IterationControl& control,
                             std::vector<double>* objective_history) {
  result_potentials_.clear();
  // These two count each segment's iterations themselves (a segment may stop before the others).
  if (control.acceleration == Acceleration::LBFGS) return solveLbfgs(c, y, x, t, control, objective_history);
  const bool plain = control.acceleration == Acceleration::None;
  if (plain && control.tolerance > 0.0 && rows_.size() > 1) return solvePlainPerSegment(c, y, x, t, control);
  int done = 0;
  if (plain) {
    done = solvePlain(c, y, x, t, control, objective_history);
  } else if (control.acceleration == Acceleration::Newton) {
    done = solveNewton(c, y, x, t, control, objective_history);
  } else {
    done = solveAccelerated(c, y, x, t, control, objective_history);
  }
  segment_iterations_.assign(std::max<std::size_t>(1, rows_.size()), done);
  return done;
}

void LocalGlobalSolver::startSegmentStops(std::size_t segments) {
  stopped_.assign(segments, 0);
  segment_iterations_.assign(segments, 0);
  running_segments_ = segments;
}

void LocalGlobalSolver::stopSegment(std::size_t s, int done) {
  stopped_[s] = 1;
  segment_iterations_[s] = done;
  --running_segments_;
}

void LocalGlobalSolver::finishSegmentStops(int done) {
  for (std::size_t s = 0; s < stopped_.size(); ++s)
    if (!stopped_[s]) segment_iterations_[s] = done;
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

// Plain iterations of a batch with the tolerance stop: each segment's objective is its scene's
// (Backend::potentials and massDots: the numbers its own Simulator's solve computes) and so is
// its stop; a segment that has stopped keeps its iterate (its rows are written back after every
// later global step) and the count at its stop, while the others go on. An energy pass per
// iteration besides the local step: the local step's own energy is the batch's sum.
int LocalGlobalSolver::solvePlainPerSegment(double c, int y, int x, double t, const IterationControl& control) {
  const std::size_t segments = rows_.size();
  std::vector<double>&previous = scalars_[0], &current = scalars_[1], &dots = scalars_[2];
  auto objectives = [&](std::vector<double>& out) {
    backend_.potentials(x, t, segment_potentials_);
    backend_.combine(scratch_, 1.0, x, -1.0, y);
    backend_.massDots(scratch_, scratch_, dots);
    out.resize(segments);
    for (std::size_t s = 0; s < segments; ++s) out[s] = 0.5 * c * dots[s] + segment_potentials_[s].total();
  };
  startSegmentStops(segments);
  objectives(previous);
  int done = 0;
  while (done < control.max_iterations) {
    localStep(c, y, x, t, control, nullptr);
    globalStep(c, x, control, /*to_host=*/true);
    ++done;
    for (std::size_t s = 0; s < segments && running_segments_ < segments; ++s)
      if (stopped_[s])
        x_host_.middleRows(rows_[s].first, rows_[s].count) = x_stopped_.middleRows(rows_[s].first, rows_[s].count);
    backend_.write(x, x_host_);
    objectives(current);
    for (std::size_t s = 0; s < segments; ++s) {
      if (stopped_[s]) continue;
      const double scale = segmentScale(control, s);
      if (std::abs(previous[s] - current[s]) <= control.tolerance * std::max(std::abs(current[s]), scale)) {
        stopSegment(s, done);
        if (x_stopped_.rows() != x_host_.rows()) x_stopped_.resize(x_host_.rows(), 3);
        x_stopped_.middleRows(rows_[s].first, rows_[s].count) = x_host_.middleRows(rows_[s].first, rows_[s].count);
      }
    }
    previous.swap(current);
    if (running_segments_ == 0) break;
  }
  finishSegmentStops(done);
  result_potentials_ = segment_potentials_;  // of slot x as it is left
  return done;
}

namespace {

// The extrapolation rules of the safeguarded loop below. Given the accepted iterate x_k and its
// plain update g = G(x_k), propose() writes x_{k+1} and returns true, or returns false to take
// g itself. start() begins a solve; rejected() follows an x_{k+1} whose objective rose (the loop
// then continues from g, the plain update of the accepted x_k).
class Extrapolation {
 public:
  virtual ~Extrapolation() = default;
  virtual void start() = 0;
  virtual void rejected() = 0;
  virtual bool propose(const Eigen::MatrixX3d& x_k, const Eigen::MatrixX3d& g, Eigen::MatrixX3d& next) = 0;
};

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

// Safeguarded acceleration: the plain update never raises the objective, an extrapolated one
// may. The local step of every iterate also returns its potential, so an iterate whose
// objective rose is replaced by the plain update of the last accepted iterate and the
// extrapolation restarts. The last iteration is always plain, so the returned x is never worse
// than any earlier iterate.
int LocalGlobalSolver::solveAccelerated(double c, int y, int x, double t, const IterationControl& control,
                                        std::vector<double>* objective_history) {
  Chebyshev chebyshev(control.chebyshev_rho);
  Anderson anderson(control.anderson_window);
  Extrapolation& rule = control.acceleration == Acceleration::Anderson ? static_cast<Extrapolation&>(anderson)
                                                                       : static_cast<Extrapolation&>(chebyshev);
  const bool to_tolerance = control.tolerance > 0.0;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  backend_.read(y, y_host_);
  backend_.read(x, x_cur_);
  if (objective_history) objective_history->clear();
  rule.start();

  double accepted_objective = 0.0;  // objective of the last accepted iterate
  bool have_accepted = false;
  bool extrapolated = false;  // x_cur_ is an extrapolated (not plain) iterate
  int done = 0;
  PotentialEnergy potential;
  while (true) {
    localStep(c, y, x, t, control, &potential);
    double current = inertia(c, x_cur_) + potential.total();
    // A rise within round-off of the objective is no rise: deciding on noise would make two
    // backends that agree to round-off take different iterates.
    const double noise = 1e-12 * std::max(std::abs(accepted_objective), control.energy_scale);
    if (extrapolated && have_accepted && !(current <= accepted_objective + noise)) {
      ++rejected_;
      x_cur_ = x_host_;  // the plain update of the last accepted iterate
      backend_.write(x, x_cur_);
      localStep(c, y, x, t, control, &potential);
      current = inertia(c, x_cur_) + potential.total();
      rule.rejected();
    }
    if (objective_history) objective_history->push_back(current);
    const bool converged =
        to_tolerance && have_accepted &&
        std::abs(accepted_objective - current) <= control.tolerance * std::max(std::abs(current), control.energy_scale);
    accepted_objective = current;
    have_accepted = true;
    if (done >= limit || converged) break;

    // x_host_ = the plain update of x_cur_ (which the host CG also starts from).
    if (control.global_solve == GlobalSolve::ConjugateGradient) x_host_ = x_cur_;
    globalStep(c, x, control, /*to_host=*/true);
    ++done;
    const bool last = done >= limit;
    extrapolated = rule.propose(x_cur_, x_host_, x_next_) && !last;
    x_cur_ = extrapolated ? x_next_ : x_host_;
    backend_.write(x, x_cur_);
    if (last && !objective_history) break;  // the final plain iterate needs no local step
  }
  return done;
}

}  // namespace stabint
