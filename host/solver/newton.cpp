// Newton-CG on the objective of one implicit solve (docs/method.md, "Newton"): the Hessian of
// every spring projected to positive semi-definite, w [n n^T + max(0, 1 - r/|u|) (I - n n^T)],
// the Projective-Dynamics matrix w A^T A for every other element, and c M: H = K_c - sum over
// springs of w min(1, r/|u|) (I - n n^T) on the spring's difference. H is positive definite and
// H <= K_c, so the conjugate gradients on H d = -g preconditioned with the prefactored K_c^-1 start
// from the plain step's direction and capture the modes where the springs' true stiffness is far
// below K_c's (a pinned cloth's swing, transverse to taut springs) in a few iterations. Each CG
// iteration is one solve with the factor and one product with H; the backtracking line search
// L-BFGS uses too (SolveContext::lineSearch) keeps the objective from rising.
#include "elements/element_type.hpp"
#include "scene/scene_data.hpp"
#include "solver/accelerations.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

namespace stabint {

namespace {
// Inexact Newton: CG stops once the residual's K_c^-1 norm has fallen to this fraction of the
// gradient's, or when the step's share of the iteration budget is spent.
constexpr double kForcing = 0.05;
constexpr int kMaxCgPerStep = 5;
}  // namespace

// The springs' transverse coefficients at ctx.x_trial: beta_e = w min(1, r/|u|) and n_e, of the
// segments still running (a batch's).
void NewtonIterations::springCurvature(SolveContext& ctx) {
  springs_.clear();
  if (ctx.scene() == nullptr) return;
  const std::vector<ElementBlock>& blocks = ctx.scene()->blocks();
  const bool some = ctx.stops.mask() && ctx.sceneSegments().size() == ctx.stops.running().size();
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    const ElementBlock& block = blocks[k];
    if (std::strcmp(block.type->identifier(), "spring") != 0) continue;
    const int params = block.type->shape().params;
    for (std::size_t s = 0; s < (some ? ctx.sceneSegments().size() : 1); ++s) {
      if (some && !ctx.stops.running()[s]) continue;
      const int first = some ? ctx.sceneSegments()[s].first_element[k] : 0;
      const int end = first + (some ? ctx.sceneSegments()[s].num_elements[k] : block.count);
      for (int e = first; e < end; ++e) {
        const int a = block.vertices[std::size_t(2 * e)], b = block.vertices[std::size_t(2 * e + 1)];
        const double w = block.params[std::size_t(params * e)], rest = block.params[std::size_t(params * e + 1)];
        const Eigen::Vector3d u = (ctx.x_trial.row(a) - ctx.x_trial.row(b)).transpose();
        const double length = u.norm();
        if (!(length > 0.0) || w == 0.0) continue;
        springs_.push_back({a, b, w * std::min(1.0, rest / length), u / length});
      }
    }
  }
}

// out = H v (the rows of the segments still running; the others' are left as they were).
void NewtonIterations::hessianTimes(SolveContext& ctx, double c, const Eigen::MatrixX3d& v,
                                    Eigen::MatrixX3d& out) const {
  ctx.system().multiply(c, v, out, ctx.stops.mask());
  for (const SpringCurvature& s : springs_) {
    const Eigen::Vector3d d = (v.row(s.a) - v.row(s.b)).transpose();
    const Eigen::Vector3d transverse = s.beta * (d - s.n * s.n.dot(d));
    out.row(s.a) -= transverse.transpose();
    out.row(s.b) += transverse.transpose();
  }
}

// Per scene segment (a batch's concatenated scenes, block-diagonal K_c and H): every segment runs
// its own CG (its dot products, step lengths and stops; a CG iteration counts against the
// segment's budget only while its CG runs), its own line search and its own tolerance stop, so a
// scene takes the steps it takes alone. The factor solves and the products with H run over the
// whole batch.
int NewtonIterations::solve(SolveContext& ctx, double c, int y, int x, double t, const IterationControl& control,
                            std::vector<double>* objective_history) {
  const Eigen::Index n = ctx.masses.size();
  ctx.coverWholeSystem();
  const std::size_t segments = ctx.rows().size();
  const bool to_tolerance = control.tolerance > 0.0;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  ctx.backend().read(y, ctx.y_host);
  ctx.backend().read(x, ctx.x_trial);
  ctx.x_cur = ctx.x_trial;
  std::vector<double>&objective = ctx.scalars[0], &trial_objective = ctx.scalars[1], &slope = ctx.scalars[2],
  &rz = ctx.scalars[3], &rz0 = ctx.scalars[4], &product = ctx.scalars[5], &step = ctx.scalars[6];
  ctx.stops.start(segments);
  ctx.localStepObjectives(c, y, x, t, objective);
  ctx.gradient = ctx.trial_gradient;
  if (objective_history) objective_history->assign(1, objective[0]);
  // CG's dot products: over the whole vectors for one segment, as a Simulator has always summed
  // them, and over copies of each segment's rows in a batch, so that they are summed as the scene
  // alone sums them (bit for bit: CG amplifies round-off).
  auto dots = [&](const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b, std::vector<double>& out) {
    if (segments == 1) {
      out.assign(1, a.cwiseProduct(b).sum());
      return;
    }
    out.resize(segments);
    for (std::size_t s = 0; s < segments; ++s) {
      ctx.segment_x = a.middleRows(ctx.rows()[s].first, ctx.rows()[s].count);
      ctx.segment_g = b.middleRows(ctx.rows()[s].first, ctx.rows()[s].count);
      out[s] = ctx.segment_x.cwiseProduct(ctx.segment_g).sum();
    }
  };
  std::vector<int>& done = ctx.stops.iterations();  // each segment's count; stopSegment keeps it
  std::vector<char>& cg_running = cg_running_;
  auto stop = [&](std::size_t s) { ctx.stops.stop(s, done[s]); };
  if (limit <= 0)
    for (std::size_t s = 0; s < segments; ++s) stop(s);

  while (ctx.stops.runningCount() > 0) {
    // CG on H d = -g, preconditioned with K_c^-1, from d = 0.
    springCurvature(ctx);
    ctx.direction.setZero(n, 3);
    ctx.search = -ctx.gradient;  // the residual
    ctx.applyInitialInverseHessian(c, control, ctx.search, cg_z_);
    cg_p_ = cg_z_;
    dots(ctx.search, cg_z_, rz);
    rz0 = rz;
    cg_running.assign(segments, 0);
    for (std::size_t s = 0; s < segments; ++s) cg_running[s] = !ctx.stops.stopped(s);
    for (int k = 0; k < kMaxCgPerStep; ++k) {
      hessianTimes(ctx, c, cg_p_, cg_hp_);
      dots(cg_p_, cg_hp_, product);  // the curvature along p
      bool any = false;
      for (std::size_t s = 0; s < segments; ++s) {
        if (!cg_running[s]) continue;
        ++done[s];
        cg_running[s] = 0;
        if (!(product[s] > 0.0)) continue;
        const double alpha = rz[s] / product[s];
        ctx.segmentRows(ctx.direction, s) += alpha * ctx.segmentRows(cg_p_, s);
        ctx.segmentRows(ctx.search, s) -= alpha * ctx.segmentRows(cg_hp_, s);
        cg_running[s] = k + 1 < kMaxCgPerStep && done[s] < limit;
        any = any || cg_running[s];
      }
      if (!any) break;
      ctx.applyInitialInverseHessian(c, control, ctx.search, cg_z_);
      dots(ctx.search, cg_z_, product);  // the new rz
      for (std::size_t s = 0; s < segments; ++s) {
        if (!cg_running[s]) continue;
        if (product[s] <= kForcing * kForcing * rz0[s]) {
          cg_running[s] = 0;
          continue;
        }
        ctx.segmentRows(cg_p_, s) = ctx.segmentRows(cg_z_, s) + (product[s] / rz[s]) * ctx.segmentRows(cg_p_, s);
        rz[s] = product[s];
      }
    }
    ctx.segmentDots(ctx.gradient, ctx.direction, slope);
    for (std::size_t s = 0; s < segments; ++s)
      if (ctx.stops.stopped(s)) slope[s] = 0.0;  // takes no step
    ctx.lineSearch(c, y, x, t, control, objective, slope, step, trial_objective);
    ctx.gradient = ctx.trial_gradient;
    ctx.x_cur = ctx.x_trial;
    for (std::size_t s = 0; s < segments; ++s) {
      if (ctx.stops.stopped(s)) continue;
      if (!ctx.moved()[s]) {
        // No decrease along the Newton direction: the segment stays at its accepted iterate.
        stop(s);
        continue;
      }
      const double change = std::abs(objective[s] - trial_objective[s]);
      objective[s] = trial_objective[s];
      if ((to_tolerance &&
           change <= control.tolerance * std::max(std::abs(objective[s]), ctx.segmentScale(control, s))) ||
          done[s] >= limit)
        stop(s);
    }
    if (objective_history) objective_history->push_back(objective[0]);
  }
  return *std::max_element(done.begin(), done.end());
}

}  // namespace stabint
