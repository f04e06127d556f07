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

void LocalGlobalSolver::setScene(const SceneData* scene) { scene_ = scene; }

// The springs' transverse coefficients at x_trial_: beta_e = w min(1, r/|u|) and n_e.
void LocalGlobalSolver::springCurvature() {
  springs_.clear();
  if (scene_ == nullptr) return;
  for (const ElementBlock& block : scene_->blocks()) {
    if (std::strcmp(block.type->identifier(), "spring") != 0) continue;
    const int params = block.type->shape().params;
    for (int e = 0; e < block.count; ++e) {
      const int a = block.vertices[std::size_t(2 * e)], b = block.vertices[std::size_t(2 * e + 1)];
      const double w = block.params[std::size_t(params * e)], rest = block.params[std::size_t(params * e + 1)];
      const Eigen::Vector3d u = (x_trial_.row(a) - x_trial_.row(b)).transpose();
      const double length = u.norm();
      if (!(length > 0.0) || w == 0.0) continue;
      springs_.push_back({a, b, w * std::min(1.0, rest / length), u / length});
    }
  }
}

// out = H v.
void LocalGlobalSolver::hessianTimes(double c, const Eigen::MatrixX3d& v, Eigen::MatrixX3d& out) const {
  system_.multiply(c, v, out);
  for (const SpringCurvature& s : springs_) {
    const Eigen::Vector3d d = (v.row(s.a) - v.row(s.b)).transpose();
    const Eigen::Vector3d transverse = s.beta * (d - s.n * s.n.dot(d));
    out.row(s.a) -= transverse.transpose();
    out.row(s.b) += transverse.transpose();
  }
}

int LocalGlobalSolver::solveNewton(double c, int y, int x, double t, const IterationControl& control,
                                   std::vector<double>* objective_history) {
  const Eigen::Index n = masses_.size();
  if (rows_.empty()) rows_.push_back({0, static_cast<int>(n)});  // one system: batches refuse Newton-CG
  const bool to_tolerance = control.tolerance > 0.0;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  backend_.read(y, y_host_);
  backend_.read(x, x_trial_);
  x_cur_ = x_trial_;
  std::vector<double>&objective = scalars_[0], &trial_objective = scalars_[1], &slope = scalars_[2],
  &step = scalars_[6];
  localStepObjectives(c, y, x, t, objective);
  gradient_ = trial_gradient_;
  if (objective_history) objective_history->assign(1, objective[0]);
  auto dot = [](const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) { return a.cwiseProduct(b).sum(); };

  int done = 0;
  while (done < limit) {
    // CG on H d = -g, preconditioned with K_c^-1, from d = 0.
    springCurvature();
    direction_.setZero(n, 3);
    search_ = -gradient_;  // the residual
    applyInitialInverseHessian(c, control, search_, cg_z_);
    cg_p_ = cg_z_;
    double rz = dot(search_, cg_z_);
    const double rz0 = rz;
    for (int k = 0; k < kMaxCgPerStep && done < limit; ++k) {
      hessianTimes(c, cg_p_, cg_hp_);
      const double curvature = dot(cg_p_, cg_hp_);
      ++done;
      if (!(curvature > 0.0)) break;
      const double alpha = rz / curvature;
      direction_ += alpha * cg_p_;
      search_ -= alpha * cg_hp_;
      if (k + 1 == kMaxCgPerStep || done >= limit) break;
      applyInitialInverseHessian(c, control, search_, cg_z_);
      const double rz_new = dot(search_, cg_z_);
      if (rz_new <= kForcing * kForcing * rz0) break;
      cg_p_ = cg_z_ + (rz_new / rz) * cg_p_;
      rz = rz_new;
    }
    segmentDots(gradient_, direction_, slope);
    lineSearch(c, y, x, t, control, objective, slope, step, trial_objective);
    if (!moved_[0]) {
      // No decrease along the Newton direction: the solve stays at the accepted iterate.
      if (objective_history) objective_history->push_back(objective[0]);
      break;
    }
    gradient_ = trial_gradient_;
    const double change = std::abs(objective[0] - trial_objective[0]);
    objective[0] = trial_objective[0];
    x_cur_ = x_trial_;
    if (objective_history) objective_history->push_back(objective[0]);
    if (to_tolerance && change <= control.tolerance * std::max(std::abs(objective[0]), control.energy_scale)) break;
  }
  return done;
}

}  // namespace stabint
