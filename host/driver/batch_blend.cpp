// The blend in lockstep (docs/method.md, section 3; docs/batch_design.md): every stepping scene's
// IM candidate from one solve, the BE partner of the scenes that need it from at most one more
// (solved on where even the whole partner keeps too much energy), and the root finds' energy
// passes shared by all scenes, one batched pass per round. Each scene's decisions are its own
// BlendStep's (blend_step.hpp), so a batch's scene blends as its own Simulator does.
#include "driver/batch_simulator.hpp"

#include "integrator/integrator_steps.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace stabint {

void BatchDriver::blend(double t1, bool forced, const std::vector<char>& steady) {
  IntegratorSteps steps(*backend_, solver_);
  const IterationControl control = iterationControl(options_.iterations);
  std::vector<char> not_finite, needs_partner;
  judgeMidpointCandidates(steps, control, t1, forced, steady, not_finite, needs_partner);
  const auto any = [](const std::vector<char>& flags) {
    return std::any_of(flags.begin(), flags.end(), [](char f) { return f != 0; });
  };
  if (any(not_finite)) replaceBlownUpCandidates(steps, control, t1, forced, not_finite);
  if (any(needs_partner)) blendWithPartner(steps, control, t1, steady, needs_partner);
}

// Every stepping scene's IM candidate from one solve, its potentials (and, with `forced`, those
// at the midpoint time that book the forcing), and its BlendStep's verdict: `not_finite` flags the
// scenes whose candidate blew up, `needs_partner` those whose candidate keeps too much energy.
void BatchDriver::judgeMidpointCandidates(IntegratorSteps& steps, const IterationControl& control, double t1,
                                          bool forced, const std::vector<char>& steady, std::vector<char>& not_finite,
                                          std::vector<char>& needs_partner) {
  const double h = options_.time_step;
  const double tm = t_ + 0.5 * h;
  const std::size_t n = segments_.size();
  const std::vector<char> stepping = steppingScenes();
  solver_.setSolving(stepping);
  solver_.setRigidModes(midpointRigidMotions(steady));
  const int im_iterations = steps.implicitMidpoint(h, t_, kXNew, kVNew, control);
  backend_->readBoth(kXNew, x_new_, kVNew, v_new_);
  backend_->potentials(kXNew, t1, p_all_, &stepping);
  if (forced) {
    backend_->potentials(kXNew, tm, new_mid_, &stepping);
    backend_->potentials(kX, tm, old_mid_, &stepping);
  }
  not_finite.assign(n, 0);
  needs_partner.assign(n, 0);
  for (std::size_t s = 0; s < n; ++s) {
    PerScene& p = per_scene_[s];
    if (!p.stepping) continue;
    StepReport& r = report_.scenes[s];
    const Eigen::VectorXd& masses = scenes_[s].masses;
    r.iterations = sceneIterations(s, im_iterations);
    r.energy_evaluations = 1;
    p.blend.start(
        BlendScene{&masses, p.momentum_conserved, p.energy_scale,
                   blendTolerance(options_, p.kinetic, p.potential, p.energy_scale),
                   std::max(0.0, p.kinetic + p.potential.total() - p.target), p.bodies.empty() ? nullptr : &p.bodies},
        options_, r);
    p.x_new = blockOf(x_new_, segments_[s]);
    p.v_new = blockOf(v_new_, segments_[s]);
    const PotentialEnergy& p_im = p_all_[s];
    const double vv_im = massDot(masses, p.v_new, p.v_new);
    if (!std::isfinite(0.5 * vv_im + p_im.total())) {
      p.blend.candidateNotFinite();
      not_finite[s] = 1;
      continue;
    }
    p.p_new = p_im;
    // The target must include this step's forcing before the candidate is judged.
    if (forced) {
      r.forcing = forcingOfStep(s, p_im, new_mid_[s], old_mid_[s], p.x_new);
      r.energy_evaluations += 2;
      p.target_now += r.forcing;
    }
    needs_partner[s] = p.blend.judge(p.x_new, p.v_new, p_im, vv_im, p.target_now) ? 1 : 0;
  }
}

// The BE step with the full budget for the scenes whose IM candidate blew up (`not_finite`), in
// kXTrial and kScratch: their candidates now, with their forcing booked.
void BatchDriver::replaceBlownUpCandidates(IntegratorSteps& steps, const IterationControl& control, double t1,
                                           bool forced, const std::vector<char>& not_finite) {
  const double h = options_.time_step;
  const double tm = t_ + 0.5 * h;
  returnReleasedContacts(not_finite);
  solver_.setSolving(not_finite);
  backend_->copy(kXTrial, kX);
  const int iterations = steps.backwardEuler(h, t_, kXTrial, kScratch, withoutRigidModes(control), /*warm_start=*/true);
  backend_->readBoth(kXTrial, x_aux_, kScratch, v_aux_);
  const bool evaluated = potentialsOfStep(steps, kXTrial, t1, not_finite);
  if (forced) backend_->potentials(kXTrial, tm, aux_mid_, &not_finite);
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    if (!not_finite[s]) continue;
    PerScene& p = per_scene_[s];
    StepReport& r = report_.scenes[s];
    r.iterations += sceneIterations(s, iterations);
    r.energy_evaluations += evaluated ? 1 : 0;
    p.x_new = blockOf(x_aux_, segments_[s]);
    p.v_new = blockOf(v_aux_, segments_[s]);
    v_new_.middleRows(segments_[s].first_particle, segments_[s].num_particles) = p.v_new;  // Simulator's kVNew
    p.p_new = p_all_[s];
    if (forced) {
      r.forcing = forcingOfStep(s, p.p_new, aux_mid_[s], old_mid_[s], p.x_new);
      r.energy_evaluations += 2;
      p.target_now += r.forcing;
    }
  }
}

// The BE partner of the scenes that need it (the others take no part in its solve), solved on
// where even the whole partner keeps too much energy, and each of those scenes' blend of its
// candidate with it.
void BatchDriver::blendWithPartner(IntegratorSteps& steps, IterationControl control, double t1,
                                   const std::vector<char>& steady, const std::vector<char>& needs_partner) {
  const std::size_t n = segments_.size();
  control.iterations = options_.be_iterations;
  returnReleasedContacts(needs_partner);
  solver_.setSolving(needs_partner);
  solver_.setRigidModes(steady);
  backend_->copy(kXPartner, kX);
  const int be_iterations =
      steps.backwardEuler(options_.time_step, t_, kXPartner, kVPartner, endingPlain(control), /*warm_start=*/true);
  backend_->readBoth(kXPartner, x_aux_, kVPartner, v_aux_);
  for (std::size_t s = 0; s < n; ++s) {
    if (!needs_partner[s]) continue;
    PerScene& p = per_scene_[s];
    report_.scenes[s].iterations += sceneIterations(s, be_iterations);
    p.blend.partnerPositions() = blockOf(x_aux_, segments_[s]);
    p.blend.partnerVelocities() = blockOf(v_aux_, segments_[s]);
    p.blend.partnerRead();
  }
  partner_potentials_ = steps.potentialsOfStep();
  extendPartner(t1, control, needs_partner, steady);
  evaluateBlendPotentials(t1, partner_potentials_);
  for (std::size_t s = 0; s < n; ++s)
    if (needs_partner[s]) {
      PerScene& p = per_scene_[s];
      p.p_new = p.blend.blend(p.x_new, p.v_new, *backend_);
      v_new_.middleRows(segments_[s].first_particle, segments_[s].num_particles) = p.v_new;  // Simulator writes it
    }
  // A batch of one forms the corrections' trial positions on the device from the blended state,
  // as Simulator does (evaluateBlendPotentials).
  if (n == 1 && needs_partner[0]) backend_->write(kXNew, per_scene_[0].x_new);
}

// [project rule] The partner is a few iterations (be_iterations) from x_n, far less converged than
// the candidate where the budget is large. Where even the partner whole keeps more energy than
// the target, the corrections take the velocities to zero, and a cloth dragged by a hand then
// froze step after step while the hand stretched it (docs/method.md, "A partner that cannot reach
// the target"). Such a partner goes on from where it stopped, warm-started: BE's objective still
// only decreases from x_n, so it cannot pile up energy, and a better-converged partner follows
// the hand as the candidate does (and takes out more of an excess the step inherited).
void BatchDriver::extendPartner(double t1, IterationControl control, const std::vector<char>& needs_partner,
                                const std::vector<char>& steady) {
  const int extra = options_.iterations - options_.be_iterations;
  if (extra <= 0 || control.tolerance > 0.0) return;  // a partner solved to tolerance is as far as it goes
  const std::size_t n = segments_.size();
  if (partner_potentials_.size() != n) {  // the solve left none: one pass, which the root find then reuses
    backend_->potentials(kXPartner, t1, partner_potentials_, &needs_partner);
    for (std::size_t s = 0; s < n; ++s) report_.scenes[s].energy_evaluations += needs_partner[s] ? 1 : 0;
  }
  std::vector<char> extend(n, 0);
  bool any = false;
  for (std::size_t s = 0; s < n; ++s) {
    extend[s] = needs_partner[s] && !per_scene_[s].blend.partnerReachesTarget(partner_potentials_[s]);
    any = any || extend[s];
  }
  if (!any) return;
  control.iterations = extra;
  solver_.setSolving(extend);
  solver_.setRigidModes(steady);
  IntegratorSteps steps(*backend_, solver_);
  const int done =
      steps.backwardEuler(options_.time_step, t_, kXPartner, kVPartner, endingPlain(control), /*warm_start=*/true);
  backend_->readBoth(kXPartner, x_aux_, kVPartner, v_aux_);
  const bool evaluated = potentialsOfStep(steps, kXPartner, t1, extend);
  for (std::size_t s = 0; s < n; ++s) {
    if (!extend[s]) continue;
    PerScene& p = per_scene_[s];
    report_.scenes[s].iterations += sceneIterations(s, done);
    report_.scenes[s].energy_evaluations += evaluated ? 1 : 0;
    p.blend.partnerPositions() = blockOf(x_aux_, segments_[s]);
    p.blend.partnerVelocities() = blockOf(v_aux_, segments_[s]);
    p.blend.partnerRead();
    partner_potentials_[s] = p_all_[s];
  }
}

void BatchDriver::evaluateBlendPotentials(double t1, const std::vector<PotentialEnergy>& partner) {
  // Rounds: as many as the scene that needs the most evaluations, not their sum. At w = 1 the
  // trial is the partner, whose potential its solve may have left (`partner`, per scene): taken
  // without a pass, as Simulator takes it.
  std::vector<char> wanting(segments_.size());
  for (;;) {
    bool any = false;
    for (std::size_t s = 0; s < segments_.size(); ++s) {
      BlendStep& b = per_scene_[s].blend;
      wanting[s] = 0;
      if (!per_scene_[s].stepping) continue;
      while (b.wantsPotential() && b.weight() == 1.0 && partner.size() == segments_.size())
        b.take(partner[s], /*evaluated=*/false);
      if (!b.wantsPotential()) continue;
      if (!any && x_trial_.rows() != x_.rows()) x_trial_ = x_;
      any = true;
      wanting[s] = 1;
      // As Backend::combine(kXTrial, 1 - w, from, w, partner) forms it (bit for bit on the CPU
      // reference; on a device, which rounds and contracts in its own way, a batch of one lets the
      // device form it from the slots that hold from() and the partner, kXNew and kXPartner, as
      // Simulator does, so that it is its Simulator bit for bit there too).
      const double w = b.weight();
      if (segments_.size() == 1)
        backend_->combine(kXTrial, 1.0 - w, kXNew, w, kXPartner);
      else
        x_trial_.middleRows(segments_[s].first_particle, segments_[s].num_particles) =
            (1.0 - w) * b.from() + w * b.partner();
    }
    if (!any) return;
    if (segments_.size() > 1) backend_->write(kXTrial, x_trial_);
    backend_->potentials(kXTrial, t1, p_all_, &wanting);
    for (std::size_t s = 0; s < segments_.size(); ++s) {
      BlendStep& b = per_scene_[s].blend;
      if (per_scene_[s].stepping && b.wantsPotential()) b.take(p_all_[s]);
    }
  }
}

}  // namespace stabint
