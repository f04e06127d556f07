// Newton-CG on the objective of one implicit solve (docs/method.md, "Newton"): the Hessian of
// every spring projected to positive semi-definite, w [n n^T + max(0, 1 - r/|u|) (I - n n^T)],
// the Projective-Dynamics matrix w A^T A for every other element, and c M: H = K_c - sum over
// springs of w min(1, r/|u|) (I - n n^T) on the spring's difference. H is positive definite and
// H <= K_c, so the conjugate gradients on H d = -g preconditioned with the prefactored K_c^-1 start
// from the plain step's direction and capture the modes where the springs' true stiffness is far
// below K_c's (a pinned cloth's swing, transverse to taut springs) in a few iterations. Each CG
// iteration is one solve with the factor and one product with H; L-BFGS's backtracking line
// search (lineSearch) keeps the objective from rising.
#include "elements/element_type.hpp"
#include "scene/scene_data.hpp"
#include "solver/local_global.hpp"

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

void LocalGlobalSolver::setScene(const SceneData& scene, const Forcing& forcing) {
  scene_ = &scene;
  forcing_ = &forcing;
}

// The springs' transverse coefficients at x_trial_: beta_e = w min(1, r/|u|) and n_e, of the
// segments still running (a batch's).
void LocalGlobalSolver::springCurvature() {
  springs_.clear();
  if (scene_ == nullptr) return;
  const std::vector<ElementBlock>& blocks = scene_->blocks();
  const bool some = runningMask() && segments_.size() == running_.size();
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    const ElementBlock& block = blocks[k];
    if (std::strcmp(block.type->identifier(), "spring") != 0) continue;
    const int params = block.type->shape().params;
    for (std::size_t s = 0; s < (some ? segments_.size() : 1); ++s) {
      if (some && !running_[s]) continue;
      const int first = some ? segments_[s].first_element[k] : 0;
      const int end = first + (some ? segments_[s].num_elements[k] : block.count);
      for (int e = first; e < end; ++e) {
        const int a = block.vertices[std::size_t(2 * e)], b = block.vertices[std::size_t(2 * e + 1)];
        const double w = block.params[std::size_t(params * e)], rest = block.params[std::size_t(params * e + 1)];
        const Eigen::Vector3d u = (x_trial_.row(a) - x_trial_.row(b)).transpose();
        const double length = u.norm();
        if (!(length > 0.0) || w == 0.0) continue;
        springs_.push_back({a, b, w * std::min(1.0, rest / length), u / length});
      }
    }
  }
}

// out = H v (the rows of the segments still running; the others' are left as they were).
void LocalGlobalSolver::hessianTimes(double c, const Eigen::MatrixX3d& v, Eigen::MatrixX3d& out) const {
  system_.multiply(c, v, out, runningMask());
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
int LocalGlobalSolver::solveNewton(double c, int y, int x, double t, const IterationControl& control,
                                   std::vector<double>* objective_history) {
  const Eigen::Index n = masses_.size();
  if (rows_.empty()) rows_.push_back({0, static_cast<int>(n)});  // one system
  const std::size_t segments = rows_.size();
  const bool to_tolerance = control.tolerance > 0.0;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  backend_.read(y, y_host_);
  backend_.read(x, x_trial_);
  x_cur_ = x_trial_;
  std::vector<double>&objective = scalars_[0], &trial_objective = scalars_[1], &slope = scalars_[2], &rz = scalars_[3],
  &rz0 = scalars_[4], &product = scalars_[5], &step = scalars_[6];
  startSegmentStops(segments);
  localStepObjectives(c, y, x, t, objective);
  gradient_ = trial_gradient_;
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
      segment_x_ = a.middleRows(rows_[s].first, rows_[s].count);
      segment_g_ = b.middleRows(rows_[s].first, rows_[s].count);
      out[s] = segment_x_.cwiseProduct(segment_g_).sum();
    }
  };
  std::vector<int>& done = segment_iterations_;  // each segment's count; stopSegment keeps it
  std::vector<char>& cg_running = cg_running_;
  auto stop = [&](std::size_t s) { stopSegment(s, done[s]); };
  if (limit <= 0)
    for (std::size_t s = 0; s < segments; ++s) stop(s);

  while (running_segments_ > 0) {
    // CG on H d = -g, preconditioned with K_c^-1, from d = 0.
    springCurvature();
    direction_.setZero(n, 3);
    search_ = -gradient_;  // the residual
    applyInitialInverseHessian(c, control, search_, cg_z_);
    cg_p_ = cg_z_;
    dots(search_, cg_z_, rz);
    rz0 = rz;
    cg_running.assign(segments, 0);
    for (std::size_t s = 0; s < segments; ++s) cg_running[s] = !stopped(s);
    for (int k = 0; k < kMaxCgPerStep; ++k) {
      hessianTimes(c, cg_p_, cg_hp_);
      dots(cg_p_, cg_hp_, product);  // the curvature along p
      bool any = false;
      for (std::size_t s = 0; s < segments; ++s) {
        if (!cg_running[s]) continue;
        ++done[s];
        cg_running[s] = 0;
        if (!(product[s] > 0.0)) continue;
        const double alpha = rz[s] / product[s];
        segmentRows(direction_, s) += alpha * segmentRows(cg_p_, s);
        segmentRows(search_, s) -= alpha * segmentRows(cg_hp_, s);
        cg_running[s] = k + 1 < kMaxCgPerStep && done[s] < limit;
        any = any || cg_running[s];
      }
      if (!any) break;
      applyInitialInverseHessian(c, control, search_, cg_z_);
      dots(search_, cg_z_, product);  // the new rz
      for (std::size_t s = 0; s < segments; ++s) {
        if (!cg_running[s]) continue;
        if (product[s] <= kForcing * kForcing * rz0[s]) {
          cg_running[s] = 0;
          continue;
        }
        segmentRows(cg_p_, s) = segmentRows(cg_z_, s) + (product[s] / rz[s]) * segmentRows(cg_p_, s);
        rz[s] = product[s];
      }
    }
    segmentDots(gradient_, direction_, slope);
    for (std::size_t s = 0; s < segments; ++s)
      if (stopped(s)) slope[s] = 0.0;  // takes no step
    lineSearch(c, y, x, t, control, objective, slope, step, trial_objective);
    gradient_ = trial_gradient_;
    x_cur_ = x_trial_;
    for (std::size_t s = 0; s < segments; ++s) {
      if (stopped(s)) continue;
      if (!moved_[s]) {
        // No decrease along the Newton direction: the segment stays at its accepted iterate.
        stop(s);
        continue;
      }
      const double change = std::abs(objective[s] - trial_objective[s]);
      objective[s] = trial_objective[s];
      if ((to_tolerance && change <= control.tolerance * std::max(std::abs(objective[s]), segmentScale(control, s))) ||
          done[s] >= limit)
        stop(s);
    }
    if (objective_history) objective_history->push_back(objective[0]);
  }
  return *std::max_element(done.begin(), done.end());
}

}  // namespace stabint
