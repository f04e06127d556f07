#pragma once
// One scene's energy-tracking blend in one step (docs/method.md, "The blend"), as a state
// machine driven by the caller, who runs the solves and the energy passes: Simulator for its
// scene, BatchSimulator for every scene of a batch in lockstep (one solve and one batched energy
// pass per round for all of them, docs/batch_design.md). The decisions, the root finds and the
// corrections are here only, so the two cannot drift.
//
// The caller's sequence in a step:
//   start(); the IM candidate (host copies x, v, its potential at t + h) and the step's forcing;
//   judge() (or candidateNotFinite(): the caller's BE solve with the full budget is the step);
//   when judge() wants the partner: the BE partner into partnerPositions()/partnerVelocities(),
//     partnerRead(), then while wantsPotential(): the potential of
//     (1 - weight()) from() + weight() partnerPositions() at t + h, take() it; then blend();
//   the caller's refusal of a non-finite state; beginCorrections(), the same potential loop,
//   finishCorrections().
// Trial positions may be formed on the device (Backend::combine of the slots holding from() and
// the partner, as Simulator does) or on the host (as BatchSimulator does): the same numbers on
// the CPU reference.
#include "backend/backend.hpp"
#include "integrator/rigid_motion.hpp"
#include "integrator/root_find.hpp"

#include <stabint/types.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <optional>
#include <vector>

namespace stabint {

/// What the blend needs of one scene for one step.
struct BlendScene {
  const Eigen::VectorXd* masses = nullptr;
  bool momentum_conserved = false;  // momentumConserved()
  double energy_scale = 0.0;        // E_scale
  /// tau = energy_tolerance (K_n + E_int,n + E_scale), of the state at the step's start.
  double tolerance = 0.0;
  /// max(0, H_n - H*_n): how far above its target the step's start already is.
  double inherited_excess = 0.0;
  /// The scene's bodies (connectedBodies) when it has more than one; null: the scene is one body.
  /// The corrections keep and restore each body's rigid motion apart.
  const std::vector<std::vector<int>>* bodies = nullptr;
};

/// No pins, no force fields, no user forces and no colliders: IM keeps linear and angular momentum.
bool momentumConserved(const Scene& scene, bool has_user_forces);
/// tau of docs/method.md section 7.
double blendTolerance(const SimulatorOptions& options, double kinetic, const PotentialEnergy& potential,
                      double energy_scale);

class BlendStep {
 public:
  /// A new step; `report` (its branch, alpha, velocity_scale, iterations are not touched,
  /// energy_evaluations counts the evaluations asked for here) lives until the step ends.
  void start(const BlendScene& scene, const SimulatorOptions& options, StepReport& report);

  /// An IM candidate that blew up is no candidate: the step is the caller's BE solve with the full
  /// iteration budget (branch BE, alpha 1, no partner, no momenta to restore).
  void candidateNotFinite();

  /// Judges the IM candidate (host copies x, v; p_im its potential at t + h; vv_im = massDot(v, v))
  /// against `target`, which holds this step's forcing. Returns true when it needs the BE
  /// partner: x and v are then kept as the IM candidate (swapped out of the caller's matrices)
  /// and the caller puts the partner's host copies in partnerPositions()/partnerVelocities() and
  /// calls partnerRead().
  bool judge(Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, const PotentialEnergy& p_im, double vv_im, double target);
  Eigen::MatrixX3d& partnerPositions() { return x_partner_; }
  Eigen::MatrixX3d& partnerVelocities() { return v_partner_; }
  void partnerRead();
  /// After partnerRead(), with the partner's potential `p`: whether the partner whole brings the
  /// energy below the target (the root find's first evaluation decides the same way). Where it
  /// does not, the caller may solve the partner on and call partnerRead() again.
  bool partnerReachesTarget(const PotentialEnergy& p) const { return excessAt(1.0, p) < 0.0; }
  /// Whether the machine wants the potential at t + h of (1 - weight()) from() + weight()
  /// partnerPositions(); the caller evaluates it and take()s it.
  bool wantsPotential() const { return wants_; }
  double weight() const { return weight_; }
  /// The IM candidate during the blend's root find, the blended positions during the position
  /// move of the corrections.
  const Eigen::MatrixX3d& from() const { return *from_; }
  const Eigen::MatrixX3d& partner() const { return x_partner_; }
  /// `evaluated`: false for a potential the caller had without an energy pass (not counted in
  /// StepReport::energy_evaluations).
  void take(const PotentialEnergy& p, bool evaluated = true);

  /// The blend's state: (x, v) = (1 - alpha) IM + alpha partner with the alpha of the root find,
  /// rounded to what the backend's slots hold; returns its potential at t + h.
  PotentialEnergy blend(Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, const Backend& storage);

  /// The corrections of the accepted state (x, v; p_new its potential), docs/method.md "The
  /// blend" step 5, up to the position move toward the partner (then wantsPotential(), with
  /// from() = x). `x` must stay in place until finishCorrections.
  void beginCorrections(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, double target, const PotentialEnergy& p_new);
  /// The rest of the corrections. Returns true when the velocities changed; x (positionsMoved())
  /// and p_new follow the position move.
  bool finishCorrections(Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, PotentialEnergy& p_new, const Backend& storage);
  bool positionsMoved() const { return positions_moved_; }

  /// After the final projection moved the accepted positions and raised their potential by
  /// `added` (> 0, energy nothing books): takes what of it lifts H = kinetic(v) + p_new above
  /// `target` out of the motion, from the non-rigid velocities first (keeping the swing), then
  /// from all of them (docs/method.md, "Final projection"). Returns true when v changed.
  bool takeOutProjectionExcess(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, double added, double target,
                               const PotentialEnergy& p_new);

 private:
  struct Evaluation {
    double alpha;
    double g;  // H(alpha) - H*
    PotentialEnergy potential;
  };
  enum class Stage { Idle, Partner, Search, Blended, Moving, Done };  // Moving: the corrections
  double kinetic(const Eigen::MatrixX3d& v) const;
  // H(alpha) - H* of the blend at weight alpha whose positions have potential p.
  double excessAt(double alpha, const PotentialEnergy& p) const { return k_alpha_.at(alpha) + p.total() - target_; }
  bool scaleVelocities(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, double kinetic_wanted, bool keep_rigid,
                       double s_min, double s_max) const;
  // The bodies' particle lists: one empty list (every particle) for a scene of one body.
  const std::vector<std::vector<int>>& bodies() const;
  // Correction 1: the IM candidate's momenta put back, body by body, with rigid velocity fields.
  void restoreMomenta(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& v) const;
  double excess(const Eigen::MatrixX3d& v) const;  // K(v) + P - H* of the corrections
  // The excess the corrections leave: the band, or the carried inherited excess.
  double excessLeft() const { return std::max(scene_.tolerance, allowance_); }
  void askNext();
  void consider(double beta, const PotentialEnergy& p);  // the position move's best so far

  BlendScene scene_;
  const SimulatorOptions* options_ = nullptr;
  StepReport* report_ = nullptr;
  Stage stage_ = Stage::Idle;
  bool wants_ = false;
  double weight_ = 0.0;
  const Eigen::MatrixX3d* from_ = nullptr;
  double target_ = 0.0;
  PotentialEnergy p_im_;
  double vv_im_ = 0.0;
  std::vector<RigidMotion> im_momenta_;  // per body
  bool im_momenta_known_ = false;
  bool partner_known_ = false;  // this step's partner: its copies and potential
  Eigen::MatrixX3d x_im_, v_im_, x_partner_, v_partner_, v_scratch_;
  KineticQuadratic k_alpha_;
  std::vector<Evaluation> evaluations_;
  std::optional<BlendWeightSearch> search_;
  bool partner_cannot_reach_target_ = false;
  PotentialEnergy partner_potential_;
  // The corrections.
  double k_before_ = 0.0;
  bool changed_ = false;
  bool over_ = false;    // the state had too much energy
  bool moving_ = false;  // the position move toward the partner was wanted
  double potential_wanted_ = 0.0;
  double allowance_ = 0.0;  // the excess above target_ the corrections leave (inherited_excess)
  PotentialEnergy best_;
  double best_beta_ = 0.0, best_g_ = 0.0;
  PotentialEnergy p_new_;
  bool positions_moved_ = false;
};

}  // namespace stabint
