#pragma once
// The batched simulator (docs/batch_design.md): many scenes stepped as one concatenation, with one
// local/global solve and one block-diagonal factor for all, and per scene its own energies,
// target H*, blend decisions, damping, forcing and refusal.
//
// Supported for now: every integrator, the blend included (its per-scene decisions in lockstep:
// blend_step.hpp), on the CPU reference, with a fixed iteration count and the factor (the
// controls that sum over the whole batch, a tolerance stop, acceleration and CG, are refused:
// they would couple the scenes, and one scene's NaN would reach the others through them).
#include "backend.hpp"
#include "integrator/blend_step.hpp"
#include "scene/scene_batch.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"
#include "solver/local_global.hpp"

#include <stabint/simulator.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace stabint {

struct BatchStepReport {
  std::vector<StepReport> scenes;  // one per scene, as its own Simulator::step reports it
  /// Per scene: empty when the scene stepped, else why its step was refused (its state kept).
  std::vector<std::string> refusals;
};

class BatchSimulator {
 public:
  /// Throws InvalidInputError for a bad scene ("scene <i>: ..."), scenes a batch cannot keep
  /// apart (concatenateScenes) or options it does not support yet.
  BatchSimulator(const std::vector<Scene>& scenes, const SimulatorOptions& options);

  /// Replaces scene `scene`'s positions and velocities (`n_s by 3`, finite), as
  /// Simulator::setState: a discontinuous event booked in that scene's H* only. A scene refused
  /// earlier becomes active again, at the batch's time. Refused (InvalidInputError, nothing
  /// changed) for BDF2, whose restart would take every scene of the batch back to BE.
  void setState(int scene, const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities);

  /// Advances every active scene one step. Never throws for a scene that blows up: that scene's
  /// step is refused (BatchStepReport::refusals), its state kept, and it stays inactive; the
  /// others step on as their own simulators would.
  const BatchStepReport& step();

  int size() const { return static_cast<int>(segments_.size()); }
  bool active(int scene) const { return per_scene_[std::size_t(scene)].active; }
  Eigen::MatrixX3d positions(int scene) const;
  Eigen::MatrixX3d velocities(int scene) const;
  double time(int scene) const { return per_scene_[std::size_t(scene)].time; }
  int stepCount(int scene) const { return per_scene_[std::size_t(scene)].steps; }
  double target(int scene) const { return per_scene_[std::size_t(scene)].target; }
  EnergyReport energy(int scene) const;
  double energyScale(int scene) const { return per_scene_[std::size_t(scene)].energy_scale; }
  const SceneSegment& segment(int scene) const { return segments_[std::size_t(scene)]; }

 private:
  struct PerScene {
    bool active = true;
    double time = 0.0;
    int steps = 0;
    double kinetic = 0.0;
    PotentialEnergy potential;  // of the accepted state at `time`
    double target = 0.0;
    double energy_scale = 0.0;
    bool momentum_conserved = false;
    double pending_event_energy = 0.0;  // booked by setState since the last step
    // This step's.
    bool stepping = false;            // active, and not refused so far in this step
    bool velocities_changed = false;  // the host copy v_new differs from kVNew's rows
    Eigen::MatrixX3d x_new, v_new;    // the candidate (the scene's rows)
    PotentialEnergy p_new;            // its potential at t + h
    double target_now = 0.0;          // H* with this step's forcing, damping
    BlendStep blend;
  };
  BatchSimulator(SceneBatch batch, const std::vector<Scene>& scenes, const SimulatorOptions& options);
  double kineticEnergy(int scene, const Eigen::MatrixX3d& v) const;
  void checkScene(int scene, const char* call) const;
  // The integrators but the blend: the candidates of every stepping scene, with their forcing.
  void integrate(double t1, bool forced);
  // The blend in lockstep: one IM solve, at most one partner solve (and one full-budget BE solve
  // when some scene's IM candidate blew up), one batched energy pass per root-find round.
  void blend(double t1, bool forced);
  // The potentials every scene's BlendStep asks for, one batched pass per round: the trial
  // positions are formed on the host (no per-scene combine on the backend interface yet).
  void evaluateBlendPotentials(double t1);
  void refuse(std::size_t s, const std::string& message);

  std::vector<Scene> scenes_;  // each scene alone: its bodies for the damping
  std::vector<SceneSegment> segments_;
  SimulatorOptions options_;
  SceneData data_;
  std::unique_ptr<Backend> backend_;
  GlobalSystem system_;
  LocalGlobalSolver solver_;
  Eigen::MatrixX3d x_, v_, x_new_, v_new_;  // host copies of the whole batch (v_new_: kVNew's)
  Eigen::MatrixX3d v_slot_;                 // what kV holds (see step())
  Eigen::MatrixX3d x_aux_, v_aux_;          // host copies of the partner or the full-budget BE solve
  Eigen::MatrixX3d x_trial_;                // the root finds' trial positions
  std::vector<PotentialEnergy> p_all_, new_mid_, old_mid_, aux_mid_;  // per-scene potentials
  double t_ = 0.0;                                                    // the batch's time (of the active scenes)
  bool has_history_ = false;                                          // BDF2: (kXPrev, kVPrev) hold the previous step
  std::vector<PerScene> per_scene_;
  BatchStepReport report_;
};

}  // namespace stabint
