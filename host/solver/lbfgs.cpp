// L-BFGS on the objective of one implicit solve, with the prefactored K_c = c M + L as its initial
// inverse Hessian (Liu, Bouaziz and Kavan 2017, "Quasi-Newton Methods for Real-Time Simulation of
// Hyperelastic Materials"; docs/method.md, "L-BFGS"). Every element has the Projective-Dynamics
// form w/2 ||A x - p(x)||^2 with p(x) the projection onto the element's rest set, whose gradient
// is w A^T (A x - p(x)); so the objective's gradient
//   g(x) = c M (x - y) - f_ext - sum_e w A^T (p(x) - A x)   (= K_c x - rhs(x))
// comes from the force form of the local step's element pass (Backend::localStepGradient): an
// iteration costs what a plain one does (one local step with its energy, one solve) plus a few
// fused passes over the history. With an empty history the direction -K_c^-1 g is the plain
// iteration's step.
//
// The two-loop recursion runs on dot products (as in Chen et al. 2014, "Large-scale L-BFGS using
// MapReduce"): each segment keeps the products s_i.y_j of its pairs, so a direction takes four
// passes over the vectors (the new pair with its products, q = g - sum a_i y_i, the products
// y_i.r after the solve, d = -(r + sum (a_i - b_i) s_i)) instead of two per stored pair.
//
// Per scene segment (a batch's concatenated scenes, block-diagonal K_c): every dot product, step
// length and history is the segment's own, so a scene takes the steps it takes alone.
#include "solver/accelerations.hpp"
#include "solver/history_passes.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace stabint {

using namespace history_passes;

// After an accepted line search: the new pair s = x_trial - x_cur, y = g_trial - g into ring slot
// `slot`, with s.y, y.y, s.s and its products with the other stored pairs (gram_[seg](i, j) =
// s_i.y_j) and s_j.g_trial for every stored pair (the next direction's first loop); and then
// x_cur = x_trial, g = g_trial. One pass over the vectors.
void LbfgsIterations::storePair(SolveContext& ctx, int slot, int stored, std::vector<double>& sy,
                                std::vector<double>& yy, std::vector<double>& ss) {
  const Eigen::Index n = ctx.x_cur.rows();
  const int window = static_cast<int>(history_s_.size());
  Eigen::MatrixX3d& s_new = history_s_[std::size_t(slot)];
  Eigen::MatrixX3d& y_new = history_y_[std::size_t(slot)];
  s_new.resize(n, 3);
  y_new.resize(n, 3);
  // The ring after this pair: `kept` slots, the new one included.
  const int kept = std::min(stored + 1, window);
  sy.assign(ctx.rows().size(), 0.0);
  yy.assign(ctx.rows().size(), 0.0);
  ss.assign(ctx.rows().size(), 0.0);
  forEachSegment(ctx.rows(), [&](std::size_t seg) {
    if (ctx.stops.stopped(seg)) return;  // no pair (its products stay 0)
    Eigen::MatrixXd& gram = gram_[seg];
    std::vector<double>& sg = history_sg_[seg];
    for (int j = 0; j < window; ++j) gram(slot, j) = gram(j, slot) = sg[std::size_t(j)] = 0.0;
    forEachChunk(ctx.rows()[seg].first, ctx.rows()[seg].count, n, [&](Eigen::Index o, int len) {
      double* s = s_new.data() + o;
      double* y = y_new.data() + o;
      const double* g_trial = ctx.trial_gradient.data() + o;
      double sums[4];
      newPair(len, ctx.x_trial.data() + o, g_trial, ctx.x_cur.data() + o, ctx.gradient.data() + o, s, y, sums);
      sy[seg] += sums[0];
      yy[seg] += sums[1];
      ss[seg] += sums[2];
      sg[std::size_t(slot)] += sums[3];
      for (int k = 1; k < kept; ++k) {
        const int j = (slot - k + window) % window;
        double products[3];
        pairProducts(len, s, y, g_trial, history_s_[std::size_t(j)].data() + o, history_y_[std::size_t(j)].data() + o,
                     products);
        gram(slot, j) += products[0];
        gram(j, slot) += products[1];
        sg[std::size_t(j)] += products[2];
      }
    });
    gram(slot, slot) = sy[seg];
  });
}

// ctx.direction = -H g by the two-loop recursion over the newest `pairs` pairs, from the products
// storePair keeps: q = g - sum a_i y_i (a_i = rho_i s_i.q_i, newest first), r = H0 q,
// d = -(r + sum (a_i - b_i) s_i) (b_i = rho_i y_i.r_i, oldest first); and each segment's slope g.d.
void LbfgsIterations::twoLoopDirection(SolveContext& ctx, double c, const IterationControl& control, int pairs,
                                       int newest, std::vector<double>& slope) {
  const Eigen::Index n = ctx.gradient.rows();
  const int window = static_cast<int>(history_s_.size());
  auto slotOf = [&](int k) { return std::size_t((newest - k + window) % window); };  // k-th newest
  ctx.search.resize(n, 3);
  forEachSegment(ctx.rows(), [&](std::size_t seg) {
    if (ctx.stops.stopped(seg)) return;  // takes no step (its slope is set to 0)
    const Eigen::MatrixXd& gram = gram_[seg];
    for (int k = 0; k < pairs; ++k) {
      const std::size_t i = slotOf(k);
      double sq = history_sg_[seg][i];
      for (int l = 0; l < k; ++l) sq -= history_alpha_[slotOf(l)][seg] * gram(Eigen::Index(i), Eigen::Index(slotOf(l)));
      history_alpha_[i][seg] = history_rho_[i][seg] * sq;
    }
    forEachChunk(ctx.rows()[seg].first, ctx.rows()[seg].count, n, [&](Eigen::Index o, int len) {
      double* q = ctx.search.data() + o;
      std::copy_n(ctx.gradient.data() + o, len, q);
      for (int k = 0; k < pairs; ++k) {
        const double a = history_alpha_[slotOf(k)][seg];
        if (a != 0.0) subtractScaled(len, q, a, history_y_[slotOf(k)].data() + o);
      }
    });
  });
  rigid_modes_.apply(ctx, c, control, ctx.search, ctx.direction);
  slope.assign(ctx.rows().size(), 0.0);
  forEachSegment(ctx.rows(), [&](std::size_t seg) {
    if (ctx.stops.stopped(seg)) return;
    thread_local std::vector<double> yr;  // y_i.r of the newest `pairs` pairs (no allocation per call)
    yr.assign(std::size_t(pairs), 0.0);
    forEachChunk(ctx.rows()[seg].first, ctx.rows()[seg].count, n, [&](Eigen::Index o, int len) {
      const double* r = ctx.direction.data() + o;
      for (int k = 0; k < pairs; ++k) yr[std::size_t(k)] += dot(len, history_y_[slotOf(k)].data() + o, r);
    });
    // The coefficient of s_i in d, oldest first; kept in history_alpha_.
    const Eigen::MatrixXd& gram = gram_[seg];
    for (int k = pairs - 1; k >= 0; --k) {
      const std::size_t i = slotOf(k);
      const double rho = history_rho_[i][seg];
      double y_r = yr[std::size_t(k)];
      for (int l = pairs - 1; l > k; --l)
        y_r += history_alpha_[slotOf(l)][seg] * gram(Eigen::Index(slotOf(l)), Eigen::Index(i));
      history_alpha_[i][seg] = rho == 0.0 ? 0.0 : history_alpha_[i][seg] - rho * y_r;
    }
    forEachChunk(ctx.rows()[seg].first, ctx.rows()[seg].count, n, [&](Eigen::Index o, int len) {
      double* d = ctx.direction.data() + o;
      for (int k = pairs - 1; k >= 0; --k) {
        const double coefficient = history_alpha_[slotOf(k)][seg];
        if (coefficient != 0.0) addScaled(len, d, coefficient, history_s_[slotOf(k)].data() + o);
      }
      slope[seg] += negateAndSlope(len, d, ctx.gradient.data() + o);
    });
  });
}

// An empty ring of `window` pairs for every segment.
void LbfgsIterations::resetHistory(int window, std::size_t segments) {
  if (static_cast<int>(history_s_.size()) != window) {
    history_s_.assign(std::size_t(window), Eigen::MatrixX3d());
    history_y_.assign(std::size_t(window), Eigen::MatrixX3d());
  }
  history_rho_.resize(std::size_t(window));
  history_alpha_.resize(std::size_t(window));
  for (int i = 0; i < window; ++i) {
    history_rho_[std::size_t(i)].assign(segments, 0.0);
    history_alpha_[std::size_t(i)].assign(segments, 0.0);
  }
  gram_.resize(segments);
  history_sg_.resize(segments);
  for (std::size_t s = 0; s < segments; ++s) {
    gram_[s].setZero(window, window);
    history_sg_[s].assign(std::size_t(window), 0.0);
  }
}

// The stopping rule by accuracy (IterationControl::gradient_tolerance): each segment's gradient
// in the norm of the current inverse Hessian H, sqrt(g.H g) = sqrt(-g.d) (the Newton decrement:
// half its square estimates the objective's distance to the minimum), against its value at the
// warm start (`initial`, set in the first iteration), where H = K_c^-1. A converged segment's
// direction is spent, but it takes no step along it (its rows of slot x and its objective stay
// the accepted iterate's).
void LbfgsIterations::stopConvergedByGradient(SolveContext& ctx, int done, const IterationControl& control,
                                              const std::vector<double>& slope, std::vector<double>& initial) {
  if (done == 1) initial.assign(ctx.rows().size(), 0.0);
  for (std::size_t s = 0; s < ctx.rows().size(); ++s) {
    if (ctx.stops.stopped(s)) continue;
    const double decrement = std::sqrt(std::max(0.0, -slope[s]));
    if (done == 1) initial[s] = decrement;
    if (done > 1 && decrement <= control.gradient_tolerance * initial[s]) ctx.stops.stop(s, done);
  }
}

// A segment the line search left where it was: with a plain direction its objective is at its
// round-off floor and it stops; else it drops its history (and the rigid motions) and restarts
// from the plain step.
void LbfgsIterations::handleStayedSegments(SolveContext& ctx, int done) {
  for (std::size_t s = 0; s < ctx.rows().size(); ++s) {
    if (ctx.moved()[s] || ctx.stops.stopped(s)) continue;
    if (plain_direction_[s]) {
      ctx.stops.stop(s, done);
    } else {
      for (auto& rho : history_rho_) rho[s] = 0.0;
      if (rigid_modes_.on(s)) rigid_modes_.drop(s);
    }
  }
}

// Per segment, after its step: the new pair in ring slot `slot` counts where its curvature s.y is
// positive (`dot`, `yy`, `ss`: its s.y, y.y, s.s), and the tolerance stop compares the objective
// before and after the step (`objective` takes `trial_objective`).
void LbfgsIterations::keepCurvaturePairs(SolveContext& ctx, int slot, int done, const IterationControl& control,
                                         const std::vector<double>& step, const std::vector<double>& dot,
                                         const std::vector<double>& yy, const std::vector<double>& ss,
                                         std::vector<double>& objective, const std::vector<double>& trial_objective) {
  const bool to_tolerance = control.tolerance > 0.0;
  for (std::size_t s = 0; s < ctx.rows().size(); ++s) {
    // Positive curvature keeps H positive definite; a pair at round-off's angle would not.
    const bool curvature = ctx.moved()[s] && std::isfinite(dot[s]) && dot[s] > 1e-10 * std::sqrt(ss[s] * yy[s]);
    history_rho_[std::size_t(slot)][s] = curvature ? 1.0 / dot[s] : 0.0;
    // A segment that stayed for want of decrease has not converged: it restarts from the plain step.
    const bool stayed = !ctx.moved()[s] && step[s] != 0.0;
    const double change = std::abs(objective[s] - trial_objective[s]);
    if (to_tolerance && !ctx.stops.stopped(s) && !stayed &&
        change <= control.tolerance * std::max(std::abs(trial_objective[s]), ctx.segmentScale(control, s)))
      ctx.stops.stop(s, done);
    objective[s] = trial_objective[s];
  }
}

int LbfgsIterations::solve(SolveContext& ctx, double c, int y, int x, double t, const IterationControl& control,
                           std::vector<double>* objective_history, const std::vector<char>& rigid) {
  ctx.coverWholeSystem();
  const std::size_t segments = ctx.rows().size();
  const bool to_tolerance = control.tolerance > 0.0;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  const int window = std::max(1, control.lbfgs_history);
  resetHistory(window, segments);
  int stored = 0, newest = -1;  // pairs in the ring, index of the newest

  ctx.backend().read(y, ctx.y_host);
  ctx.backend().read(x, ctx.x_trial);
  ctx.x_cur = ctx.x_trial;
  std::vector<double>&objective = ctx.scalars[0], &trial_objective = ctx.scalars[1], &slope = ctx.scalars[2],
  &dot = ctx.scalars[3], &yy = ctx.scalars[4], &ss = ctx.scalars[5], &step = ctx.scalars[6];
  step.resize(segments);
  // A segment whose stop (by accuracy) was met takes no more steps: it stays at the iterate it
  // stopped at, with the iterations done by then, as the scene alone stops its solve there. One
  // that takes no part (setSolving) is stopped from the start.
  ctx.stops.start(segments);
  ctx.localStepObjectives(c, y, x, t, objective);
  ctx.gradient = ctx.trial_gradient;
  rigid_modes_.prepare(ctx, c, t, control, rigid);
  std::vector<double>& initial_decrement = ctx.scalars[7];
  if (objective_history) objective_history->assign(1, objective[0]);

  int done = 0;
  auto usesHistory = [&](std::size_t s) {
    for (const auto& rho : history_rho_)
      if (rho[s] != 0.0) return true;
    return false;
  };
  plain_direction_.assign(segments, 0);
  while (done < limit) {
    // [project rule] Where the integrator asks for it (implicit midpoint, BDF2, the blend's
    // partner) the last iteration of a budget is a plain one (the direction of the empty
    // history): it smooths the error that the curvature pairs leave in stiff, high-frequency
    // modes, which IM's x_1 = 2 x_mid - x_n doubles and BDF2's history carries on as elastic
    // energy; without it the blend could not bring a dragged cloth back into its energy band.
    // In BE the last L-BFGS step is worth more (docs/method.md, "L-BFGS").
    const int pairs = control.plain_last_iteration && !to_tolerance && done == limit - 1 ? 0 : stored;
    twoLoopDirection(ctx, c, control, pairs, newest, slope);
    ++done;
    if (control.gradient_tolerance > 0.0) {
      stopConvergedByGradient(ctx, done, control, slope, initial_decrement);
      if (ctx.stops.runningCount() == 0) break;
    }
    for (std::size_t s = 0; s < segments; ++s) {
      if (ctx.stops.stopped(s)) slope[s] = 0.0;  // no step (lineSearch)
      // The plain step is K_c^-1's alone: the rigid motions' coarse space, like a curvature pair,
      // is a guess the line search may reject.
      plain_direction_[s] = (pairs == 0 || !usesHistory(s)) && !rigid_modes_.on(s);
    }
    // With positive curvature pairs H is positive definite and the direction descends; a slope
    // >= 0 is round-off (or a converged segment). A segment that does not move restarts from the
    // plain step. A plain step decreases the objective in exact arithmetic (f(x + d) <= f(x) -
    // 1/2 d^T K_c d); where even it does not, the segment's objective is at its round-off floor
    // (in float on a device, long before the budget: the objective's round-off is 1e-7 of it), and
    // every later iteration would try the same step again: the segment stops there. One whose
    // direction used the rigid motions drops them too for the rest of the solve.
    ctx.lineSearch(c, y, x, t, control, objective, slope, step, trial_objective);
    handleStayedSegments(ctx, done);

    // The curvature pair of the step, kept where s.y > 0.
    const int slot = (newest + 1) % window;
    if (done < limit) {
      storePair(ctx, slot, stored, dot, yy, ss);
    } else {  // the solve's last pair would never be used
      for (std::vector<double>* v : {&dot, &yy, &ss}) v->assign(segments, 0.0);
    }
    keepCurvaturePairs(ctx, slot, done, control, step, dot, yy, ss, objective, trial_objective);
    newest = slot;
    stored = std::min(stored + 1, window);
    if (objective_history) objective_history->push_back(objective[0]);
    if (ctx.stops.runningCount() == 0) break;
    // Pairs that leave the contact set hold no energy at the iterate: the objective, its gradient
    // and the curvature pairs stay, and the directions take the new K_c. The rigid motions' coarse
    // space holds the pairs' weights: a segment whose set changed drops it. A pair that returns
    // with its particle inside adds its energy: the segment's objective and gradient are those of
    // a local step at the iterate again, and its curvature pairs, taken without it, are dropped.
    bool release = false;
    const std::vector<char> changed = ctx.changeContacts(c, done, limit, x, t, release);
    if (std::find(changed.begin(), changed.end(), 1) == changed.end()) continue;
    for (std::size_t s = 0; s < changed.size(); ++s) {
      if (!changed[s]) continue;
      if (rigid_modes_.on(s)) rigid_modes_.drop(s);
      if (!release)
        for (auto& rho : history_rho_) rho[s] = 0.0;
    }
    if (!release) {
      ctx.localStepObjectives(c, y, x, t, objective);
      ctx.gradient = ctx.trial_gradient;
    }
  }
  ctx.stops.finish(done);
  return done;
}

}  // namespace stabint
