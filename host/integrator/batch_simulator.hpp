#pragma once
// The batched simulator's first step (docs/batch_design.md, step 3 in part): many scenes stepped
// as one concatenation, with one local/global solve and one block-diagonal factor for all, and
// per scene its own energies, target H*, damping, forcing and refusal. Internal until it has the
// blend and the OpenCL backend; then it moves to include/stabint/batch.hpp.
//
// Supported for now: every integrator but the blend, on the CPU reference, with a fixed
// iteration count and the factor (the controls that sum over the whole batch, a tolerance stop,
// acceleration and CG, are refused: they would couple the scenes, and one scene's NaN would reach
// the others through them).
#include "backend.hpp"
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
  };
  BatchSimulator(SceneBatch batch, const std::vector<Scene>& scenes, const SimulatorOptions& options);
  double kineticEnergy(int scene, const Eigen::MatrixX3d& v) const;
  // Scene s's forcing work (new_mid, old_mid: potentials at t_m, null when no forcing changes),
  // damping and refusal checks; on acceptance its new energies and target.
  void acceptOrRefuse(std::size_t s, const PotentialEnergy* new_mid, const PotentialEnergy* old_mid,
                      const PotentialEnergy& p_new, double t1, StepReport& r, bool& rows_changed);

  std::vector<Scene> scenes_;  // each scene alone: its bodies for the damping
  std::vector<SceneSegment> segments_;
  SimulatorOptions options_;
  SceneData data_;
  std::unique_ptr<Backend> backend_;
  GlobalSystem system_;
  LocalGlobalSolver solver_;
  Eigen::MatrixX3d x_, v_, x_new_, v_new_;  // host copies of the whole batch
  double t_ = 0.0;                          // the batch's time (of the active scenes)
  bool has_history_ = false;                // BDF2: (kXPrev, kVPrev) hold the previous step
  std::vector<PerScene> per_scene_;
  BatchStepReport report_;
};

}  // namespace stabint
