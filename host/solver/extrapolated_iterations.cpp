// Safeguarded extrapolation of the plain iterations (docs/method.md, "Acceleration"): Chebyshev's
// semi-iteration and Anderson's mixing, one rule per scene segment.
#include "solver/accelerations.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <memory>

namespace stabint {

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

ExtrapolatedIterations::ExtrapolatedIterations() = default;
ExtrapolatedIterations::~ExtrapolatedIterations() = default;

// One rule per segment, kept from one solve to the next (their vectors are reused): new ones only
// when the rule, its constant or the segments change.
void ExtrapolatedIterations::prepare(const IterationControl& control, std::size_t segments) {
  const bool anderson = control.acceleration == Acceleration::Anderson;
  const double constant = anderson ? control.anderson_window : control.chebyshev_rho;
  if (extrapolations_.size() == segments && key_ == std::make_pair(anderson, constant)) return;
  extrapolations_.clear();
  for (std::size_t s = 0; s < segments; ++s) {
    if (anderson)
      extrapolations_.push_back(std::make_unique<Anderson>(control.anderson_window));
    else
      extrapolations_.push_back(std::make_unique<Chebyshev>(control.chebyshev_rho));
  }
  key_ = {anderson, constant};
}

// The local step at slot x (= ctx.x_cur) and every segment's objective there. One segment: the whole
// scene's pass and inertia, as a Simulator has always computed them.
void ExtrapolatedIterations::objectives(SolveContext& ctx, double c, int y, int x, double t,
                                        const IterationControl& control, std::vector<double>& objective) {
  if (ctx.rows().size() <= 1) {
    PotentialEnergy potential;
    ctx.localStep(c, y, x, t, control, &potential);
    objective.assign(1, ctx.inertia(c, ctx.x_cur) + potential.total());
    return;
  }
  ctx.backend().localStepRhsPerScene(x, y, c, t, ctx.rhs, ctx.segment_potentials, ctx.stops.mask());
  objective.resize(ctx.rows().size());
  for (std::size_t s = 0; s < ctx.rows().size(); ++s)
    objective[s] = ctx.segmentInertia(c, ctx.x_cur, s) + ctx.segment_potentials[s].total();
}

// SegmentRows s's extrapolation from its rows of ctx.x_cur (x_k) and ctx.x_host (g) into ctx.x_next. One
// segment works on the whole matrices; a batch's segments on copies of their rows, so that each
// rule sees the vectors its scene alone has.
bool ExtrapolatedIterations::propose(SolveContext& ctx, std::size_t s) {
  Extrapolation& rule = *extrapolations_[s];
  if (ctx.rows().size() <= 1) return rule.propose(ctx.x_cur, ctx.x_host, ctx.x_next);
  const SegmentRows& seg = ctx.rows()[s];
  ctx.segment_x = ctx.x_cur.middleRows(seg.first, seg.count);
  ctx.segment_g = ctx.x_host.middleRows(seg.first, seg.count);
  const bool extrapolated = rule.propose(ctx.segment_x, ctx.segment_g, segment_next_);
  if (extrapolated) ctx.x_next.middleRows(seg.first, seg.count) = segment_next_;
  return extrapolated;
}

// Safeguarded acceleration: the plain update never raises the objective, an extrapolated one
// may. The local step of every iterate also returns its potential, so an iterate whose
// objective rose is replaced by the plain update of the last accepted iterate and the
// extrapolation restarts. The last iteration is always plain, so the returned x is never worse
// than any earlier iterate. In a batch every segment has its own rule, objective, rejections and
// tolerance stop (a stopped segment keeps its iterate while the others go on), so a scene takes
// the iterates it takes alone.
int ExtrapolatedIterations::solve(SolveContext& ctx, double c, int y, int x, double t, const IterationControl& control,
                                  std::vector<double>* objective_history) {
  const std::size_t segments = std::max<std::size_t>(1, ctx.rows().size());
  prepare(control, segments);
  const bool to_tolerance = control.tolerance > 0.0;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  ctx.backend().read(y, ctx.y_host);
  ctx.backend().read(x, ctx.x_cur);
  if (ctx.x_next.rows() != ctx.x_cur.rows()) ctx.x_next.resize(ctx.x_cur.rows(), 3);
  if (objective_history) objective_history->clear();
  for (auto& rule : extrapolations_) rule->start();
  ctx.stops.start(segments);

  std::vector<double>&accepted_objective = ctx.scalars[0], &current = ctx.scalars[1];  // of the last accepted iterate
  accepted_objective.assign(segments, 0.0);
  bool have_accepted = false;
  extrapolated_.assign(segments, 0);  // ctx.x_cur's rows of the segment are extrapolated (not plain)
  int done = 0;
  while (true) {
    objectives(ctx, c, y, x, t, control, current);
    bool rejected = false;
    for (std::size_t s = 0; s < segments; ++s) {
      if (ctx.stops.stopped(s)) continue;
      // A rise within round-off of the objective is no rise: deciding on noise would make two
      // backends that agree to round-off take different iterates.
      const double noise = 1e-12 * std::max(std::abs(accepted_objective[s]), ctx.segmentScale(control, s));
      if (extrapolated_[s] && have_accepted && !(current[s] <= accepted_objective[s] + noise)) {
        ++rejected_;
        rejected = true;
        ctx.segmentRows(ctx.x_cur, s) =
            ctx.segmentRows(ctx.x_host, s);  // the plain update of the last accepted iterate
        extrapolations_[s]->rejected();
      }
    }
    if (rejected) {
      ctx.backend().write(x, ctx.x_cur);
      objectives(ctx, c, y, x, t, control, current);
    }
    if (objective_history) objective_history->push_back(current[0]);
    for (std::size_t s = 0; s < segments; ++s) {
      if (ctx.stops.stopped(s)) continue;
      const bool converged = to_tolerance && have_accepted &&
                             std::abs(accepted_objective[s] - current[s]) <=
                                 control.tolerance * std::max(std::abs(current[s]), ctx.segmentScale(control, s));
      accepted_objective[s] = current[s];
      if (converged) ctx.stops.stop(s, done);
    }
    have_accepted = true;
    if (done >= limit || ctx.stops.runningCount() == 0) break;

    // ctx.x_host = the plain update of ctx.x_cur (which the host CG also starts from).
    if (control.global_solve == GlobalSolve::ConjugateGradient) ctx.x_host = ctx.x_cur;
    ctx.globalStep(c, x, control, /*to_host=*/true);
    ++done;
    const bool last = done >= limit;
    for (std::size_t s = 0; s < segments; ++s) {
      if (ctx.stops.stopped(s)) continue;  // its rows of ctx.x_cur stay at its last iterate
      extrapolated_[s] = propose(ctx, s) && !last;
      ctx.segmentRows(ctx.x_cur, s) =
          extrapolated_[s] ? ctx.segmentRows(ctx.x_next, s) : ctx.segmentRows(ctx.x_host, s);
    }
    ctx.backend().write(x, ctx.x_cur);
    if (last && !objective_history) break;  // the final plain iterate needs no local step
  }
  ctx.stops.finish(done);
  return done;
}

}  // namespace stabint
