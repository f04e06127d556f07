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
#include "solver/local_global.hpp"

#include "solver/history_passes.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace stabint {

using namespace history_passes;

namespace {

// Armijo's sufficient-decrease constant. A plain step satisfies the test with any constant up to
// 1/2 (f(x + d) <= f(x) - 1/2 d^T K_c d, d = -K_c^-1 g), so an empty history always passes.
constexpr double kArmijo = 1e-4;
// Halvings of a step that fails the test before the segment stays where it is for this iteration
// and drops its history (its next direction is the plain step).
constexpr int kMaxHalvings = 4;

}  // namespace

void LocalGlobalSolver::setSegments(const std::vector<SceneSegment>& segments,
                                    const std::vector<double>& energy_scales) {
  rows_.clear();
  for (const SceneSegment& s : segments) rows_.push_back({s.first_particle, s.num_particles});
  segments_ = segments;
  system_.setBlocks(segments);  // a batch's host CG per scene
  segment_scales_ = energy_scales;
}

void LocalGlobalSolver::segmentDots(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b,
                                    std::vector<double>& out) const {
  out.resize(rows_.size());
  for (std::size_t s = 0; s < rows_.size(); ++s) {
    const Segment& seg = rows_[s];
    out[s] = a.middleRows(seg.first, seg.count).cwiseProduct(b.middleRows(seg.first, seg.count)).sum();
  }
}

// The objective of every segment at the positions x_trial_ (already in slot x), from the local
// step that also leaves the gradient there in trial_gradient_.
void LocalGlobalSolver::localStepObjectives(double c, int y, int x, double t, std::vector<double>& objective) {
  objective.resize(rows_.size());
  if (rows_.size() == 1) {
    PotentialEnergy potential;
    backend_.localStepGradient(x, y, c, t, trial_gradient_, &potential);
    objective[0] = inertia(c, x_trial_) + potential.total();
    result_potentials_.assign(1, potential);
    return;
  }
  backend_.localStepGradientPerScene(x, y, c, t, trial_gradient_, segment_potentials_, runningMask());
  keepResultPotentials();
  for (std::size_t s = 0; s < rows_.size(); ++s)
    objective[s] = segmentInertia(c, x_trial_, s) + segment_potentials_[s].total();
}

void LocalGlobalSolver::applyInitialInverseHessian(double c, const IterationControl& control, const Eigen::MatrixX3d& q,
                                                   Eigen::MatrixX3d& r) {
  const auto start = std::chrono::steady_clock::now();
  if (control.global_solve == GlobalSolve::ConjugateGradient) {
    r.setZero(q.rows(), 3);
    system_.solveConjugateGradient(c, q, r, control.cg_iterations, control.cg_tolerance, runningMask());
  } else {
    system_.solve(c, q, r, runningMask());
  }
  backend_.times().global += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Backtracking line search from x_cur_ along direction_, per segment: the full step where
// f(x + a d) <= f(x) + kArmijo a g.d up to round-off of the objective (two backends that agree to
// round-off must take the same decisions), else halved up to kMaxHalvings times. A segment whose
// slope is not negative takes no step (step 0); one that finds no decrease stays (step != 0).
// Leaves x_trial_, slot x and trial_gradient_ at the kept positions, their objectives in `trial_objective`
// and the segments that moved in moved_.
void LocalGlobalSolver::lineSearch(double c, int y, int x, double t, const IterationControl& control,
                                   const std::vector<double>& objective, const std::vector<double>& slope,
                                   std::vector<double>& step, std::vector<double>& trial_objective) {
  const std::size_t segments = rows_.size();
  step.resize(segments);
  // A segment that takes no step keeps its objective (when none steps, no local step runs).
  trial_objective = objective;
  accepted_.assign(segments, 0);
  moved_.assign(segments, 0);
  for (std::size_t s = 0; s < segments; ++s) {
    step[s] = slope[s] < 0.0 ? 1.0 : 0.0;
    accepted_[s] = step[s] == 0.0;
  }
  for (int halving = 0; halving <= kMaxHalvings; ++halving) {
    bool any_trial = false;
    for (std::size_t s = 0; s < segments; ++s) {
      if (accepted_[s]) continue;
      segmentRows(x_trial_, s) = segmentRows(x_cur_, s) + step[s] * segmentRows(direction_, s);
      any_trial = true;
    }
    if (!any_trial) break;
    backend_.roundToStorage(x_trial_);
    backend_.write(x, x_trial_);
    localStepObjectives(c, y, x, t, trial_objective);
    for (std::size_t s = 0; s < segments; ++s) {
      if (accepted_[s]) continue;
      const double scale = segmentScale(control, s);
      const double noise = 1e-12 * std::max(std::abs(objective[s]), scale);
      if (trial_objective[s] <= objective[s] + kArmijo * step[s] * slope[s] + noise) {
        accepted_[s] = 1;
        moved_[s] = 1;
      } else if (halving < kMaxHalvings) {
        step[s] *= 0.5;
      } else {
        accepted_[s] = 1;
        segmentRows(x_trial_, s) = segmentRows(x_cur_, s);
      }
    }
  }
  // Slot x and trial_gradient_ must be at the kept positions: a segment that stayed changed slot x in its
  // trials, so one more local step at them.
  bool any_stayed = false;
  for (std::size_t s = 0; s < segments; ++s) any_stayed |= !moved_[s] && step[s] != 0.0;
  if (any_stayed) {
    backend_.write(x, x_trial_);
    localStepObjectives(c, y, x, t, trial_objective);
  }
}

// After an accepted line search: the new pair s = x_trial - x_cur, y = g_trial - g into ring slot
// `slot`, with s.y, y.y, s.s and its products with the other stored pairs (gram_[seg](i, j) =
// s_i.y_j) and s_j.g_trial for every stored pair (the next direction's first loop); and then
// x_cur = x_trial, g = g_trial. One pass over the vectors.
void LocalGlobalSolver::storePair(int slot, int stored, std::vector<double>& sy, std::vector<double>& yy,
                                  std::vector<double>& ss) {
  const Eigen::Index n = x_cur_.rows();
  const int window = static_cast<int>(history_s_.size());
  Eigen::MatrixX3d& s_new = history_s_[std::size_t(slot)];
  Eigen::MatrixX3d& y_new = history_y_[std::size_t(slot)];
  s_new.resize(n, 3);
  y_new.resize(n, 3);
  // The ring after this pair: `kept` slots, the new one included.
  const int kept = std::min(stored + 1, window);
  sy.assign(rows_.size(), 0.0);
  yy.assign(rows_.size(), 0.0);
  ss.assign(rows_.size(), 0.0);
  forEachSegment(rows_, [&](std::size_t seg) {
    if (stopped(seg)) return;  // no pair (its products stay 0)
    Eigen::MatrixXd& gram = gram_[seg];
    std::vector<double>& sg = history_sg_[seg];
    for (int j = 0; j < window; ++j) gram(slot, j) = gram(j, slot) = sg[std::size_t(j)] = 0.0;
    forEachChunk(rows_[seg].first, rows_[seg].count, n, [&](Eigen::Index o, int len) {
      double* s = s_new.data() + o;
      double* y = y_new.data() + o;
      const double* g_trial = trial_gradient_.data() + o;
      double sums[4];
      newPair(len, x_trial_.data() + o, g_trial, x_cur_.data() + o, gradient_.data() + o, s, y, sums);
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

// direction_ = -H g by the two-loop recursion over the newest `pairs` pairs, from the products
// storePair keeps: q = g - sum a_i y_i (a_i = rho_i s_i.q_i, newest first), r = H0 q,
// d = -(r + sum (a_i - b_i) s_i) (b_i = rho_i y_i.r_i, oldest first); and each segment's slope g.d.
void LocalGlobalSolver::lbfgsDirection(double c, const IterationControl& control, int pairs, int newest,
                                       std::vector<double>& slope) {
  const Eigen::Index n = gradient_.rows();
  const int window = static_cast<int>(history_s_.size());
  auto slotOf = [&](int k) { return std::size_t((newest - k + window) % window); };  // k-th newest
  search_.resize(n, 3);
  forEachSegment(rows_, [&](std::size_t seg) {
    if (stopped(seg)) return;  // takes no step (its slope is set to 0)
    const Eigen::MatrixXd& gram = gram_[seg];
    for (int k = 0; k < pairs; ++k) {
      const std::size_t i = slotOf(k);
      double sq = history_sg_[seg][i];
      for (int l = 0; l < k; ++l) sq -= history_alpha_[slotOf(l)][seg] * gram(Eigen::Index(i), Eigen::Index(slotOf(l)));
      history_alpha_[i][seg] = history_rho_[i][seg] * sq;
    }
    forEachChunk(rows_[seg].first, rows_[seg].count, n, [&](Eigen::Index o, int len) {
      double* q = search_.data() + o;
      std::copy_n(gradient_.data() + o, len, q);
      for (int k = 0; k < pairs; ++k) {
        const double a = history_alpha_[slotOf(k)][seg];
        if (a != 0.0) subtractScaled(len, q, a, history_y_[slotOf(k)].data() + o);
      }
    });
  });
  applyTwoLevelInverse(c, control, search_, direction_);
  slope.assign(rows_.size(), 0.0);
  forEachSegment(rows_, [&](std::size_t seg) {
    if (stopped(seg)) return;
    thread_local std::vector<double> yr;  // y_i.r of the newest `pairs` pairs (no allocation per call)
    yr.assign(std::size_t(pairs), 0.0);
    forEachChunk(rows_[seg].first, rows_[seg].count, n, [&](Eigen::Index o, int len) {
      const double* r = direction_.data() + o;
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
    forEachChunk(rows_[seg].first, rows_[seg].count, n, [&](Eigen::Index o, int len) {
      double* d = direction_.data() + o;
      for (int k = pairs - 1; k >= 0; --k) {
        const double coefficient = history_alpha_[slotOf(k)][seg];
        if (coefficient != 0.0) addScaled(len, d, coefficient, history_s_[slotOf(k)].data() + o);
      }
      slope[seg] += negateAndSlope(len, d, gradient_.data() + o);
    });
  });
}

// An empty ring of `window` pairs for every segment.
void LocalGlobalSolver::resetLbfgsHistory(int window, std::size_t segments) {
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
void LocalGlobalSolver::stopConvergedByGradient(int done, const IterationControl& control,
                                                const std::vector<double>& slope, std::vector<double>& initial) {
  if (done == 1) initial.assign(rows_.size(), 0.0);
  for (std::size_t s = 0; s < rows_.size(); ++s) {
    if (stopped(s)) continue;
    const double decrement = std::sqrt(std::max(0.0, -slope[s]));
    if (done == 1) initial[s] = decrement;
    if (done > 1 && decrement <= control.gradient_tolerance * initial[s]) stopSegment(s, done);
  }
}

// A segment the line search left where it was: with a plain direction its objective is at its
// round-off floor and it stops; else it drops its history (and the rigid motions) and restarts
// from the plain step.
void LocalGlobalSolver::handleStayedSegments(int done) {
  for (std::size_t s = 0; s < rows_.size(); ++s) {
    if (moved_[s] || stopped(s)) continue;
    if (plain_direction_[s]) {
      stopSegment(s, done);
    } else {
      for (auto& rho : history_rho_) rho[s] = 0.0;
      if (usesRigidModes(s)) rigid_on_[s] = 0;
    }
  }
}

// Per segment, after its step: the new pair in ring slot `slot` counts where its curvature s.y is
// positive (`dot`, `yy`, `ss`: its s.y, y.y, s.s), and the tolerance stop compares the objective
// before and after the step (`objective` takes `trial_objective`).
void LocalGlobalSolver::keepCurvaturePairs(int slot, int done, const IterationControl& control,
                                           const std::vector<double>& step, const std::vector<double>& dot,
                                           const std::vector<double>& yy, const std::vector<double>& ss,
                                           std::vector<double>& objective, const std::vector<double>& trial_objective) {
  const bool to_tolerance = control.tolerance > 0.0;
  for (std::size_t s = 0; s < rows_.size(); ++s) {
    // Positive curvature keeps H positive definite; a pair at round-off's angle would not.
    const bool curvature = moved_[s] && std::isfinite(dot[s]) && dot[s] > 1e-10 * std::sqrt(ss[s] * yy[s]);
    history_rho_[std::size_t(slot)][s] = curvature ? 1.0 / dot[s] : 0.0;
    // A segment that stayed for want of decrease has not converged: it restarts from the plain step.
    const bool stayed = !moved_[s] && step[s] != 0.0;
    const double change = std::abs(objective[s] - trial_objective[s]);
    if (to_tolerance && !stopped(s) && !stayed &&
        change <= control.tolerance * std::max(std::abs(trial_objective[s]), segmentScale(control, s)))
      stopSegment(s, done);
    objective[s] = trial_objective[s];
  }
}

int LocalGlobalSolver::solveLbfgs(double c, int y, int x, double t, const IterationControl& control,
                                  std::vector<double>* objective_history) {
  const Eigen::Index n = masses_.size();
  if (rows_.empty()) rows_.push_back({0, static_cast<int>(n)});
  const std::size_t segments = rows_.size();
  const bool to_tolerance = control.tolerance > 0.0;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  const int window = std::max(1, control.lbfgs_history);
  resetLbfgsHistory(window, segments);
  int stored = 0, newest = -1;  // pairs in the ring, index of the newest

  backend_.read(y, y_host_);
  backend_.read(x, x_trial_);
  x_cur_ = x_trial_;
  std::vector<double>&objective = scalars_[0], &trial_objective = scalars_[1], &slope = scalars_[2], &dot = scalars_[3],
  &yy = scalars_[4], &ss = scalars_[5], &step = scalars_[6];
  step.resize(segments);
  // A segment whose stop (by accuracy) was met takes no more steps: it stays at the iterate it
  // stopped at, with the iterations done by then, as the scene alone stops its solve there. One
  // that takes no part (setSolving) is stopped from the start.
  startSegmentStops(segments);
  localStepObjectives(c, y, x, t, objective);
  gradient_ = trial_gradient_;
  prepareRigidModes(c, t, control);
  std::vector<double>& initial_decrement = scalars_[7];
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
    lbfgsDirection(c, control, pairs, newest, slope);
    ++done;
    if (control.gradient_tolerance > 0.0) {
      stopConvergedByGradient(done, control, slope, initial_decrement);
      if (running_segments_ == 0) break;
    }
    for (std::size_t s = 0; s < segments; ++s) {
      if (stopped(s)) slope[s] = 0.0;  // no step (lineSearch)
      // The plain step is K_c^-1's alone: the rigid motions' coarse space, like a curvature pair,
      // is a guess the line search may reject.
      plain_direction_[s] = (pairs == 0 || !usesHistory(s)) && !usesRigidModes(s);
    }
    // With positive curvature pairs H is positive definite and the direction descends; a slope
    // >= 0 is round-off (or a converged segment). A segment that does not move restarts from the
    // plain step. A plain step decreases the objective in exact arithmetic (f(x + d) <= f(x) -
    // 1/2 d^T K_c d); where even it does not, the segment's objective is at its round-off floor
    // (in float on a device, long before the budget: the objective's round-off is 1e-7 of it), and
    // every later iteration would try the same step again: the segment stops there. One whose
    // direction used the rigid motions drops them too for the rest of the solve.
    lineSearch(c, y, x, t, control, objective, slope, step, trial_objective);
    handleStayedSegments(done);

    // The curvature pair of the step, kept where s.y > 0.
    const int slot = (newest + 1) % window;
    if (done < limit) {
      storePair(slot, stored, dot, yy, ss);
    } else {  // the solve's last pair would never be used
      for (std::vector<double>* v : {&dot, &yy, &ss}) v->assign(segments, 0.0);
    }
    keepCurvaturePairs(slot, done, control, step, dot, yy, ss, objective, trial_objective);
    newest = slot;
    stored = std::min(stored + 1, window);
    if (objective_history) objective_history->push_back(objective[0]);
    if (running_segments_ == 0) break;
  }
  finishSegmentStops(done);
  return done;
}

}  // namespace stabint
