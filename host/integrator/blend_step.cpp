#include "integrator/blend_step.hpp"

#include "integrator/integrator_steps.hpp"

#include <algorithm>
#include <cmath>

namespace stabint {

bool momentumConserved(const Scene& scene, bool has_user_forces) {
  const bool pinned = std::any_of(scene.pins.begin(), scene.pins.end(), [](const Pin& p) { return p.stiffness > 0.0; });
  return !pinned && scene.force_fields.empty() && !has_user_forces && scene.colliders.empty();
}

double blendTolerance(const SimulatorOptions& options, double kinetic, const PotentialEnergy& potential,
                      double energy_scale) {
  return options.energy_tolerance * (kinetic + potential.elastic() + energy_scale);
}

void BlendStep::start(const BlendScene& scene, const SimulatorOptions& options, StepReport& report) {
  scene_ = scene;
  options_ = &options;
  report_ = &report;
  report.branch = BlendBranch::ImplicitMidpoint;
  report.alpha = 0.0;
  stage_ = Stage::Idle;
  wants_ = false;
  from_ = nullptr;
  im_momenta_known_ = false;
  partner_known_ = false;
  partner_cannot_reach_target_ = false;
  search_.reset();
  evaluations_.clear();
  moving_ = false;
  over_ = false;
  positions_moved_ = false;
}

double BlendStep::kinetic(const Eigen::MatrixX3d& v) const { return kineticEnergy(*scene_.masses, v); }

void BlendStep::candidateNotFinite() {
  report_->branch = BlendBranch::BackwardEuler;
  report_->alpha = 1.0;
  stage_ = Stage::Blended;
}

bool BlendStep::judge(Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, const PotentialEnergy& p_im, double vv_im,
                      double target) {
  target_ = target;
  p_im_ = p_im;
  vv_im_ = vv_im;
  stage_ = Stage::Blended;
  const double h_im = 0.5 * vv_im + p_im.total();
  if (std::abs(h_im - target) <= scene_.tolerance) return false;
  if (h_im < target) {
    report_->branch = BlendBranch::VelocityScale;  // the corrections scale the velocities up
    return false;
  }
  // Too much energy: blend with backward Euler from (x_n, v_n). [project rule] The partner's
  // iterations start at x_n, where the BE objective equals H_n and can only decrease, so a few
  // iterations cannot pile up elastic energy (docs/method.md has the measurements).
  report_->branch = BlendBranch::BackwardEuler;
  x_im_.swap(x);
  v_im_.swap(v);
  im_momenta_.clear();
  for (const std::vector<int>& body : bodies()) im_momenta_.push_back(rigidMotion(*scene_.masses, x_im_, v_im_, body));
  im_momenta_known_ = true;
  stage_ = Stage::Partner;
  return true;
}

void BlendStep::partnerRead() {
  partner_known_ = true;
  // H(alpha) = K(alpha) + P(alpha). The kinetic part is an exact quadratic in alpha:
  // K = 1/2 (vv + 2 alpha vd + alpha^2 dd) with d = v_partner - v_IM.
  v_scratch_ = 1.0 * v_partner_ + -1.0 * v_im_;  // as Backend::combine(d, 1, partner, -1, IM) forms it
  const Eigen::VectorXd& m = *scene_.masses;
  k_alpha_ = KineticQuadratic{vv_im_, massDot(m, v_im_, v_scratch_), massDot(m, v_scratch_, v_scratch_)};
  // The partner whole first: its potential is also the far end of the position move.
  stage_ = Stage::Search;
  from_ = &x_im_;
  weight_ = 1.0;
  wants_ = true;
}

void BlendStep::askNext() {
  wants_ = search_ && !search_->done();
  if (wants_) weight_ = search_->next();
}

void BlendStep::consider(double beta, const PotentialEnergy& p) {
  if (std::abs(p.total() - potential_wanted_) < std::abs(best_g_))
    best_ = p, best_beta_ = beta, best_g_ = p.total() - potential_wanted_;
}

void BlendStep::take(const PotentialEnergy& p, bool evaluated) {
  if (evaluated) ++report_->energy_evaluations;
  if (stage_ == Stage::Search) {
    evaluations_.push_back({weight_, excessAt(weight_, p), p});
    if (evaluations_.size() == 1) {
      partner_potential_ = p;
      partner_cannot_reach_target_ = evaluations_.front().g >= 0.0;
      if (!partner_cannot_reach_target_ && std::abs(evaluations_.front().g) > scene_.tolerance)
        search_.emplace(k_alpha_, target_, 0.0, p_im_.total(), 1.0, p.total(), scene_.tolerance,
                        options_->max_root_evaluations);
    } else {
      search_->take(weight_, p.total());
    }
  } else {  // Stage::Moving
    consider(weight_, p);
    search_->take(weight_, p.total());
  }
  askNext();
}

PotentialEnergy BlendStep::blend(Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, const Backend& storage) {
  // The best evaluation; the partner whole when even it has too much energy. When the root find
  // runs out of evaluations the residual is left to the velocity scale of the corrections.
  Evaluation accepted = evaluations_.front();
  if (!partner_cannot_reach_target_)
    for (const Evaluation& e : evaluations_)
      if (std::abs(e.g) < std::abs(accepted.g)) accepted = e;
  report_->alpha = accepted.alpha;
  // As Backend::combine forms it (bit for bit on the CPU reference; a device's own combine may
  // round differently, by an ulp), rounded to what the slots hold.
  const double w = accepted.alpha;
  x = (1.0 - w) * x_im_ + w * x_partner_;
  storage.roundToStorage(x);
  v = (1.0 - w) * v_im_ + w * v_partner_;
  storage.roundToStorage(v);
  stage_ = Stage::Blended;
  return accepted.potential;
}

double BlendStep::excess(const Eigen::MatrixX3d& v) const { return kinetic(v) + p_new_.total() - target_; }

const std::vector<std::vector<int>>& BlendStep::bodies() const {
  static const std::vector<std::vector<int>> whole_scene(1);
  return scene_.bodies ? *scene_.bodies : whole_scene;
}

void BlendStep::restoreMomenta(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v) const {
  const std::vector<std::vector<int>>& parts = bodies();
  for (std::size_t b = 0; b < parts.size(); ++b)
    setMomenta(rigidMotion(*scene_.masses, x, v, parts[b]), im_momenta_[b].momentum,
               im_momenta_[b].angularMomentumAboutOrigin(), x, v, parts[b]);
}

// Scales v (its non-rigid part, each body's own, when keep_rigid) so that the kinetic energy
// approaches `kinetic_wanted`, with the factor clamped to [s_min, s_max]. Returns true when it
// scaled.
bool BlendStep::scaleVelocities(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, double kinetic_wanted, bool keep_rigid,
                                double s_min, double s_max) const {
  const double k = kinetic(v);
  double k_rigid = 0.0;
  Eigen::MatrixX3d kept = Eigen::MatrixX3d::Zero(v.rows(), 3);
  if (keep_rigid) {
    for (const std::vector<int>& body : bodies()) {
      const RigidMotion rigid = rigidMotion(*scene_.masses, x, v, body);
      k_rigid += rigid.kinetic;
      const auto keep = [&](Eigen::Index j) { kept.row(j) = rigid.velocityAt(x.row(j).transpose()).transpose(); };
      if (body.empty())
        for (Eigen::Index j = 0; j < v.rows(); ++j) keep(j);
      for (int j : body) keep(j);
    }
  }
  const double k_scaled = k - k_rigid;
  if (!(k_scaled > 1e-14 * std::max(k, scene_.energy_scale))) return false;
  const double s = std::clamp(std::sqrt(std::max(0.0, kinetic_wanted - k_rigid) / k_scaled), s_min, s_max);
  for (Eigen::Index j = 0; j < v.rows(); ++j) v.row(j) = kept.row(j) + s * (v.row(j) - kept.row(j));
  return true;
}

// The blend's corrections of the accepted state, so that the energy it keeps is motion [project
// rules, docs/method.md]:
// 1. after a BE blend, the IM candidate's linear and angular momentum are put back with a rigid
//    velocity field: the partner, a few iterations from x_n, would otherwise stop the swing of
//    a pendulum-like body at every blend. Body by body (BlendScene::bodies), as everywhere a rigid
//    part is kept: the solve moves a scene's bodies apart, and one field over a turning bar and
//    the cloth under it threw the cloth up to 8 m;
// 2. too little energy: the velocities are scaled up, by at most max_velocity_scale per step:
//    where the scene conserves momentum (no pins, no force fields) only their non-rigid part,
//    which carries no momentum, elsewhere all of it. This replaces the forward-Euler partner,
//    whose explicit forces put the missing energy into stretch and flicker;
// 3. too much energy: removed first from the non-rigid velocities (keeping the swing), then
//    from the stretch, by moving the positions toward the BE partner's, and only then from the
//    rigid velocities.
void BlendStep::beginCorrections(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, double target,
                                 const PotentialEnergy& p_new) {
  target_ = target;
  // [project rule] Where even the partner whole keeps more energy than the target, the step takes
  // out what it would add to the excess its start already had (when that was above the band),
  // not the whole excess: that excess sits in the stretch, which a body stopped at every step
  // cannot give up (a poked cloth then hung frozen for seconds); the partner's BE steps take it out
  // as the body moves (docs/method.md, "A partner that cannot reach the target").
  allowance_ = partner_known_ && partner_cannot_reach_target_ && scene_.inherited_excess > scene_.tolerance
                   ? scene_.inherited_excess
                   : 0.0;
  p_new_ = p_new;
  changed_ = false;
  moving_ = false;
  over_ = false;
  positions_moved_ = false;
  wants_ = false;
  const BlendBranch branch = report_->branch;
  if (branch == BlendBranch::ImplicitMidpoint || branch == BlendBranch::None) {
    stage_ = Stage::Done;
    return;
  }
  stage_ = Stage::Moving;
  k_before_ = kinetic(v);
  // Not where an excess is left in a pinned or driven scene: the candidate's momenta would add to
  // it. A scene that conserves momentum keeps it.
  if (branch == BlendBranch::BackwardEuler && im_momenta_known_ && report_->alpha > 0.0 &&
      (allowance_ == 0.0 || scene_.momentum_conserved)) {
    restoreMomenta(x, v);
    changed_ = true;
  }
  const double tau = scene_.tolerance;
  const double over = excessLeft();
  if (excess(v) < -tau) {
    changed_ |= scaleVelocities(x, v, target_ - p_new_.total(), /*keep_rigid=*/scene_.momentum_conserved, 1.0,
                                options_->max_velocity_scale);
  } else if (excess(v) > over) {
    over_ = true;
    changed_ |= scaleVelocities(x, v, target_ + allowance_ - p_new_.total(), /*keep_rigid=*/true, 0.0, 1.0);
    // Only toward this step's partner: after a non-finite IM candidate the state is the BE solve
    // itself and there is no partner.
    if (excess(v) > over && branch == BlendBranch::BackwardEuler && partner_known_) {
      // Moves the blended positions toward the partner's, which carry less elastic energy, until
      // their potential is `potential_wanted_` or they reach the partner's. Velocities stay.
      moving_ = true;
      potential_wanted_ = target_ + allowance_ - kinetic(v);
      best_ = p_new_;
      best_beta_ = 0.0;
      best_g_ = p_new_.total() - potential_wanted_;
      // At beta = 1 the trial positions are the partner's bit for bit (0 x + 1 y), whose
      // potential the blend's root find has evaluated already.
      consider(1.0, partner_potential_);
      search_.reset();
      if (partner_potential_.total() - potential_wanted_ < -tau)
        search_.emplace(KineticQuadratic{}, potential_wanted_, 0.0, p_new_.total(), 1.0, partner_potential_.total(),
                        tau, options_->max_root_evaluations);
      from_ = &x;
      askNext();
    }
  }
}

bool BlendStep::finishCorrections(Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, PotentialEnergy& p_new,
                                  const Backend& storage) {
  if (stage_ == Stage::Done) return false;  // IM accepted: nothing to correct
  stage_ = Stage::Done;
  wants_ = false;
  if (moving_) {
    if (best_beta_ > 0.0) {
      x = (1.0 - best_beta_) * x + best_beta_ * x_partner_;
      storage.roundToStorage(x);
      positions_moved_ = true;
    }
    p_new_ = best_;
    // Moving the positions moved the angular momentum about the origin with them.
    // (Not counted as a change of the velocities, as before the blend was shared; it matters only
    // when nothing else changed them: alpha = 0 and no non-rigid motion.)
    if (scene_.momentum_conserved && im_momenta_known_) restoreMomenta(x, v);
  }
  if (over_ && excess(v) > excessLeft() && !scene_.momentum_conserved)
    changed_ |= scaleVelocities(x, v, target_ + allowance_ - p_new_.total(), /*keep_rigid=*/false, 0.0, 1.0);
  if (k_before_ > 0.0) report_->velocity_scale = std::sqrt(kinetic(v) / k_before_);
  p_new = p_new_;
  return changed_;
}

// [project rule] The energy the final projection adds (lifting particles out of a collider,
// stretching the elements it moves them against) is no input and no loss: where it lifts H above
// H*, the step pays for it out of its motion at once, as the blend's own correction 3 would, so
// that H never runs above H* for want of a rule; at most what the projection added, never below
// H*, and only down to zero motion (an excess the velocities cannot pay stays for the next steps'
// blends to take out of the stretch).
bool BlendStep::takeOutProjectionExcess(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, double added, double target,
                                        const PotentialEnergy& p_new) {
  const double k = kinetic(v);
  const double take = std::min(added, k + p_new.total() - target);
  if (!(take > 0.0) || !(k > 0.0)) return false;
  const double wanted = k - take;
  bool changed = scaleVelocities(x, v, wanted, /*keep_rigid=*/true, 0.0, 1.0);
  if (kinetic(v) > wanted * (1.0 + 1e-12)) changed |= scaleVelocities(x, v, wanted, /*keep_rigid=*/false, 0.0, 1.0);
  if (changed) report_->velocity_scale *= std::sqrt(kinetic(v) / k);
  return changed;
}

}  // namespace stabint
