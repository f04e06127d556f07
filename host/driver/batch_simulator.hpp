#pragma once
// The batched simulator's implementation (docs/batch_design.md): many scenes stepped as one concatenation, with one
// local/global solve and one block-diagonal factor for all, and per scene its own energies,
// target H*, blend decisions, damping, forcing and refusal.
//
// Supported for now: every integrator, the blend included (its per-scene decisions in lockstep:
// blend_step.hpp), colliders (each scene's on its own particles: one ContactResolver for the
// batch, its energies booked per scene), per-frame input and element changes of one scene
// (batch_input.cpp: Simulator's FrameInput and ElementChanges on the scene's segment), on any
// backend that computes per-scene energies (the
// CPU reference and OpenCL), with every solver option, each run per scene (its reductions, stops
// and CG on its own block), so that one scene's NaN never reaches the others.
#include "backend/backend.hpp"
#include "contact/contact_resolver.hpp"
#include "contact/self_contact.hpp"
#include "driver/backend_choice.hpp"
#include "integrator/blend_step.hpp"
#include "state/checkpoint.hpp"
#include "driver/element_changes.hpp"
#include "driver/frame_input.hpp"
#include "driver/input_scope.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_batch.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"
#include "solver/local_global.hpp"

#include <stabint/batch.hpp>
#include <stabint/simulator.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace stabint {

class IntegratorSteps;
struct StepRefusal;

// The segment's rows (so that its reductions run as the scene alone's, on an `n_s by 3` matrix).
// As a view: assigned to a per-scene matrix of the same size, it copies the rows without
// allocating a new matrix per scene and step (heap traffic O(scenes) per batch step).
inline auto blockOf(const Eigen::MatrixX3d& m, const SceneSegment& s) {
  return m.middleRows(s.first_particle, s.num_particles);
}

// The one stepping driver: BatchSimulator's (its Impl, below) and, as a batch of one, Simulator's
// (forSimulator, simulator.cpp). Its state is its own: the facades read it through the accessors
// below.
class BatchDriver {
 public:
  /// Throws InvalidInputError for a bad scene ("scene <i>: ..."), scenes a batch cannot keep
  /// apart (concatenateScenes) or options it does not support yet.
  BatchDriver(const std::vector<Scene>& scenes, const SimulatorOptions& options);
  /// A Simulator's driver (simulator.cpp): `scene` alone as the batch's one segment (its
  /// SceneData is the scene's own, not a concatenation), every option its Simulator takes, and
  /// Simulator's semantics where a batch's differ (`as_simulator_`).
  static std::unique_ptr<BatchDriver> forSimulator(const Scene& scene, const SimulatorOptions& options);

  /// Throws NonFiniteStateError or EnergyLimitError for a refused step of a Simulator's driver,
  /// before anything is committed; a batch books the refusal instead (refuse()).
  const BatchStepReport& step();
  /// The iteration budget of every later solve (>= 1, InvalidInputError otherwise).
  void setIterations(int iterations);
  std::string backendDescription() const;

  // ---- per-frame input and element changes of one scene (batch_input.cpp) ----------------------
  // Simulator's FrameInput and ElementChanges on the scene's segment: its indices, its rows, its
  // block of the factor; the events are booked in its H* only.
  /// The scene's scope for `call` (InvalidInputError for a scene out of range).
  InputScope scope(int scene, const char* call) const;
  FrameInput frameInput(int scene, const char* call);
  ElementChanges elementChanges(int scene, const char* call);
  void setState(int scene, const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities);
  void setStates(const std::vector<int>& scenes, const std::vector<Eigen::MatrixX3d>& positions,
                 const std::vector<Eigen::MatrixX3d>& velocities);
  // setState's parts: the checks; the new rows into the host copies as the slots will hold them
  // (returns H before them); rows [first, end) of the host copies to the slots; the event booked
  // from the new potential.
  void checkState(int scene, const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities, const char* call);
  double storeState(int scene, const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities);
  void writeStateRows(int first, int end);
  void bookState(int scene, double h_before, const PotentialEnergy& potential);
  void setExternalForces(int scene, const Eigen::MatrixX3d& forces);
  int grab(int scene, int vertex, double stiffness);
  void release(int scene, int pin);
  void changeElements(int scene, ElementKind kind, const std::vector<int>& indices, const double* stiffness,
                      bool enabled);
  // A change of the scene's elements (`change`, which validates before it changes anything) as an
  // event of that scene, as Simulator's; a scene out of range is refused first, naming `call`.
  template <typename Change>
  void changeElementsAsEvent(int scene, const char* call, Change&& change);
  // H* and the pending event energy of the scene move by the jump of H from h_before.
  void bookEvent(int scene, double h_before);
  // An element change books its event later: H after the change needs the scene's potential, a
  // backend pass and, on a device, a wait, which the changes of many scenes before a step then
  // share (one potentialsOf). Whatever reads a scene's energies or H*, or changes its positions,
  // pins or time, settles them first, and a second change of an unsettled scene settles the
  // first: every event is what an evaluation right after its change books, bit for bit.
  void settleEvents();
  // The scene's own copy follows the batch's pins (a grab, a release, a pin's stiffness), and
  // with it whether the scene conserves momentum.
  void pinsChanged(int scene);

  int size() const { return static_cast<int>(segments_.size()); }
  /// Throws InvalidInputError unless 0 <= scene < size().
  void checkScene(int scene, const char* call) const;
  /// The scene a Simulator shows (Simulator::scene): data_'s, without the support collider
  /// self-contact adds (valid until the next call).
  const Scene& publicScene() const;
  Eigen::MatrixX3d positions(int scene) const;
  Eigen::MatrixX3d velocities(int scene) const;
  /// The scene's energies (its events settled).
  EnergyReport energy(int scene);
  /// The scene's H* (its events settled).
  double target(int scene);

  // A scene's book (time, steps, energies of the accepted state, H*, the pending event energy:
  // what its checkpoint saves and restores as one value), and what the driver derives or keeps
  // for the step.
  struct PerScene : SceneBook {
    bool active = true;
    double energy_scale = 0.0;
    bool momentum_conserved = false;
    // The scene's bodies (connectedBodies), empty where the scene is one body.
    std::vector<std::vector<int>> bodies;
    bool has_user_forces = false;  // setExternalForces was called for the scene
    bool event_unsettled = false;  // an element change's event waits for settleEvents
    double h_before_event = 0.0;   // H before that change
    // This step's.
    bool stepping = false;            // active, and not refused so far in this step
    bool velocities_changed = false;  // the host copy v_new differs from kVNew's rows
    Eigen::MatrixX3d x_new, v_new;    // the candidate (the scene's rows)
    PotentialEnergy p_new;            // its potential at t + h
    double target_now = 0.0;          // H* with this step's forcing, damping
    BlendStep blend;
  };
  // ---- checkpoints (driver/batch_checkpoint.cpp) --------------------------------------------------
  // Simulator's CheckpointData twice over: the batch's state as a Simulator of the concatenation
  // would save it (its pins, forcing, elements and contact log: what ElementChanges and
  // ContactResolver restore), and each scene's part of it as a Simulator of the scene alone would
  // (cut and spliced by host/state/checkpoint_slices.hpp).
  CheckpointData batchData();
  /// Scene `scene`'s checkpoint (its part of `all`, batchData()'s) in Simulator's format: what
  /// Simulator::checkpoint and both of BatchSimulator's return.
  Checkpoint checkpointOf(const CheckpointData& all, int scene) const;
  /// What scene `scene`'s checkpoint must fit (InvalidInputError naming `call` for a scene out of
  /// range); its messages start with "<call>: scene <s>: ".
  RestoreTarget restoreTarget(int scene, const char* call) const;
  void restoreScene(int scene, const CheckpointData& d);
  void restoreAll(double time, const std::vector<CheckpointData>& scenes);
  // A float device holds coordinates and speeds up to validation::kMaxMagnitudeFloat (1e15), not
  // the scene's 1e150: InvalidInputError, prefixed `where`, for a checkpoint's state or collider
  // motion beyond what the backend holds (per-frame input checks its own).
  void checkDeviceRange(const CheckpointData& d, const std::string& where) const;
  // The state `all` with its segments and per-scene values, as Simulator::applyCheckpoint applies
  // its own: with `assemble`, L is assembled from the contact flags of the log's start and the
  // log replayed; else the elements that differ are updated in the factor.
  void apply(const CheckpointData& all, const std::vector<SceneSegment>& segments,
             const std::vector<PerScene>& per_scene, bool assemble);
  // Scene p's values as its checkpoint has them: active when at the batch's time `time` (its
  // E_scale stays its own, as a Simulator's does).
  static void restoreScalars(PerScene& p, const CheckpointData& d, double time);
  // Checked, then applied; a refusal puts the state before back through the same path, and L
  // and the factors as they were (GlobalSystem::Transaction). `where` prefixes the refusals that
  // only applying shows (a system that does not factor).
  void restoreChecked(const CheckpointData& all, const std::vector<SceneSegment>& segments,
                      const std::vector<PerScene>& per_scene, bool assemble, const std::string& where);

  // What the facades read of the state: the batch's time, a scene's book and segment, the options,
  // and the whole batch's host copies of the accepted state.
  double time() const { return t_; }
  const PerScene& book(int scene) const { return per_scene_[std::size_t(scene)]; }
  const SceneSegment& segment(int scene) const { return segments_[std::size_t(scene)]; }
  const SimulatorOptions& options() const { return options_; }
  const Eigen::MatrixX3d& allPositions() const { return x_; }
  const Eigen::MatrixX3d& allVelocities() const { return v_; }

 private:
  BatchDriver(SceneBatch batch, const std::vector<Scene>& scenes, const SimulatorOptions& options);
  double kineticEnergy(int scene, const Eigen::MatrixX3d& v) const;
  // step()'s parts: each scene's report and H* for the step to t1 (an inactive scene does not
  // step); the stepping scenes' damping, energy check and new scalars, or their refusal; the new
  // state of the batch in the slots and host copies, the BDF2 history and the time.
  void startScenes(double t1);
  void acceptScenes(double t1);
  void commit(double t1);
  // The integrators but the blend: the candidates of every stepping scene, with their forcing.
  // `forced`: some scene's forcing changes over the step; `steady`: one flag per scene, its
  // forcing does not (its solves take the rigid motions; midpointRigidMotions adds forced scenes
  // for implicit midpoint's).
  void integrate(double t1, bool forced, const std::vector<char>& steady);
  // One flag per scene: its implicit-midpoint solves take the rigid motions (`steady`: its
  // forcing is constant over the step).
  std::vector<char> midpointRigidMotions(const std::vector<char>& steady) const;
  IterationControl iterationControl(int iterations) const;
  // Scene s's iterations in the solve that did `done` (LocalGlobalSolver::segmentIterations).
  int sceneIterations(std::size_t s, int done) const;
  // One flag per scene: it steps (the solves of the others' blocks are not run).
  std::vector<char> steppingScenes() const;
  // The blend in lockstep (batch_blend.cpp): one IM solve, at most one partner solve (and one full-budget BE solve
  // when some scene's IM candidate blew up), one batched energy pass per root-find round.
  void blend(double t1, bool forced, const std::vector<char>& steady);
  // blend()'s three stages: the IM candidates and their verdicts; the full-budget BE step of the
  // scenes whose candidate blew up; the partner solve and the blends.
  void judgeMidpointCandidates(IntegratorSteps& steps, const IterationControl& control, double t1, bool forced,
                               const std::vector<char>& steady, std::vector<char>& not_finite,
                               std::vector<char>& needs_partner);
  void replaceBlownUpCandidates(IntegratorSteps& steps, const IterationControl& control, double t1, bool forced,
                                const std::vector<char>& not_finite);
  void blendWithPartner(IntegratorSteps& steps, IterationControl control, double t1, const std::vector<char>& steady,
                        const std::vector<char>& needs_partner);
  // The partner solve of the scenes whose partner, whole, still has more energy than the target:
  // on from where it stopped, up to the candidate's budget (partner_potentials_ then holds every
  // partner scene's potential).
  void extendPartner(double t1, IterationControl control, const std::vector<char>& needs_partner,
                     const std::vector<char>& steady);
  // The potentials every scene's BlendStep asks for, one batched pass per round: the trial
  // positions are formed on the host (no per-scene combine on the backend interface yet).
  void evaluateBlendPotentials(double t1, const std::vector<PotentialEnergy>& partner = {});
  bool potentialsOfStep(const IntegratorSteps& steps, int slot, double t1, const std::vector<char>& which);
  // ---- contact (driver/batch_contact.cpp) ---------------------------------------------------
  // Scene s's colliders on host copies whose row 0 is particle `first_row` (0: the batch's).
  ContactPart contactPart(std::size_t s, int first_row) const;
  // The forcing of scene s over the step to its candidate x1 (its own rows): the forcing rule's
  // sum from its potentials, with its moving colliders' share taken by the midpoint rule
  // (contactWork) instead.
  double forcingOfStep(std::size_t s, const PotentialEnergy& p_new, const PotentialEnergy& new_mid,
                       const PotentialEnergy& old_mid, const Eigen::MatrixX3d& x1) const;
  // The broad phase of the stepping scenes at the step's start from (x_, v_), as Simulator's (an
  // inactive scene's set stays as its refusal left it), then bookContactGeometry.
  void updateContactSets();
  // The pairs' geometry (ContactResolver::refreshHalfSpaces) of the stepping scenes from the
  // state just committed, then bookContactGeometry; their step reports follow.
  void refreshContactGeometry();
  // The contact set's changes within a solve (SolveContext::ContactChange) in the scenes flagged
  // in `running` (one flag per segment) that step and have colliders: the pairs the iterate in
  // `slot` carries away from their colliders leave (`release`), or those that left and are
  // inside again return; one flag per segment whose set changed.
  std::vector<char> changeContactsInSolve(int slot, const Eigen::MatrixX3d& forces, double t,
                                          const std::vector<char>& running, bool release);
  // The pairs the solves of this step released in the flagged scenes enter the set again
  // (ContactResolver::returnReleased): the blend's partner starts from the step's set.
  void returnReleasedContacts(const std::vector<char>& scenes);
  // The stepping scenes with colliders, and their parts on the whole scene's host copies.
  std::vector<std::size_t> contactScenes(std::vector<ContactPart>& parts) const;
  // Scenes[i] with changed[i] get the potential of x_ at t_ again; a loss is booked in H* and
  // StepReport::contact_projection.
  void bookContactGeometry(const std::vector<std::size_t>& scenes, const std::vector<char>& changed);
  // Self-contact before the solve: the stepping scenes' approach speeds that would bring their
  // surfaces nearer than the thickness over the step are removed from the velocities at the
  // step's start (SelfContact::stopApproach), the loss booked in H* and the slots rewritten.
  void stopSelfContactApproach();
  // Scene s's particles that self-contact's impulses leave alone: those its active pins hold.
  std::vector<int> pinnedVertices(std::size_t s) const;
  // Friction and the final projection of every stepping scene on its candidate, booked in its
  // own target, as Simulator's after its corrections; one energy pass for the projected scenes.
  void resolveContact(double t1);
  // Self-contact's resolve of scene s's candidate `x`, `v` (its segment's rows) at t1: the
  // colliders' projection runs after each round of its impulses (an impulse may push a particle
  // back into a collider), and the particles a collider holds keep its normal.
  SelfContactResult resolveSelfContact(std::size_t s, double t1, Eigen::MatrixX3d& x, Eigen::MatrixX3d& v);
  // What self-contact's correction of scene s adds to H: `potential` (of the corrected positions)
  // above the potential of the solve's candidate (PerScene::p_new), less `kinetic_removed`, the
  // kinetic energy its impulses removed.
  double selfContactGain(std::size_t s, const PotentialEnergy& potential, double kinetic_removed) const;
  // Where self-contact's pushes after the solve added more than a scene's band: the elements
  // relax around the pushed particles, held on planes through where they were pushed, and
  // self-contact runs again (docs/method.md, "Self-contact"). `before_self`: per scene the
  // candidate self-contact corrected (empty: none), `self_kinetic` what its impulses removed and
  // `potentials` those of x_trial_, both updated for the scenes relaxed.
  void relaxSelfContactPushes(double t1, const std::vector<Eigen::MatrixX3d>& before_self,
                              std::vector<double>& self_kinetic, std::vector<PotentialEnergy>& potentials);
  void holdPushedParticles(const SceneSegment& seg, const Eigen::MatrixX3d& unpushed,
                           std::vector<SupportPlane>& planes) const;
  bool relaxOnce(double t1, const std::vector<char>& relax, const std::vector<ContactResolver::Supports>& supports,
                 std::vector<Eigen::MatrixX3d>& unpushed, std::vector<double>& self_kinetic,
                 std::vector<PotentialEnergy>& potentials);
  // Rounds of relaxSelfContactPushes at most: each round's pushes start from the last's relaxed
  // positions and add their planes to the last's (a 10x cloth landing on a cloth took out 91, 65,
  // 60 and 90 % of what its pushes added in 4 rounds; 3 left it 5 bands above H*).
  static constexpr int kRelaxRounds = 5;
  // The least share of what a round found that it must take out for another round to run: a
  // converged BE step of the crumpling cloth whose first round took out 40 % of 1.6 J ended 0.87 J
  // above H* when a round had to take out half; two more rounds took it below H*.
  static constexpr double kRelaxProgress = 0.1;
  // Scene s's step is refused: the scene stops stepping (a batch keeps it inactive, its state and
  // time at the refusal); a Simulator's driver throws instead.
  void refuse(std::size_t s, const StepRefusal& refusal);

  std::vector<Scene> scenes_;  // each scene alone: its bodies for the damping, its pins as the batch's
  std::vector<SceneSegment> segments_;
  SimulatorOptions options_;
  SceneData data_;
  mutable Scene public_scene_;  // publicScene's copy, where data_'s holds support colliders
  Forcing forcing_;             // data_'s: pin targets, forces and collider motion
  BackendSelection choice_;
  std::unique_ptr<Backend> backend_;
  GlobalSystem system_;
  LocalGlobalSolver solver_;
  Eigen::MatrixX3d x_, v_, x_new_, v_new_;  // host copies of the whole batch (v_new_: kVNew's)
  Eigen::MatrixX3d v_slot_;                 // what kV holds (see step())
  // Whether x_ and v_slot_ are what kX and kV hold to the bit. After construction and a restore
  // they hold the values the slots were written from, which a float device holds rounded; the
  // first setState rounds them all (once), so that the host copies of every scene are the slots'
  // after any scene's setState, whichever rows it writes; a step keeps them so (its candidates
  // come from the slots or are rounded to them).
  bool host_copies_stored_ = false;
  ContactResolver contact_;                // every scene's colliders, each on its own particles
  std::vector<SelfContact> self_contact_;  // per scene (none when self_contact_thickness is 0)
  // InvalidInputError, prefixed `where`, when scene s's surface crosses itself at `positions`
  // (crossingTriangles): self-contact cannot undo a crossing.
  void checkNoCrossings(std::size_t s, const Eigen::MatrixX3d& positions, const std::string& where) const;
  // Per scene, this step's self-contact supports (its rows), for their friction after the solve.
  std::vector<std::vector<SupportPlane>> step_supports_;
  Eigen::MatrixX3d x_aux_, v_aux_;  // host copies of the partner or the full-budget BE solve
  Eigen::MatrixX3d x_release_;      // the iterate changeContactsInSolve reads
  Eigen::MatrixX3d x_trial_;        // the root finds' trial positions
  std::vector<PotentialEnergy> p_all_, new_mid_, old_mid_, aux_mid_;  // per-scene potentials
  std::vector<PotentialEnergy> partner_potentials_;                   // of the BE partner, when its solve left them
  double t_ = 0.0;                                                    // the batch's time (of the active scenes)
  bool has_history_ = false;                                          // BDF2: (kXPrev, kVPrev) hold the previous step
  bool restart_history_ = false;  // BDF2: self-contact corrected this step, the next is a BE step
  std::vector<PerScene> per_scene_;
  // Per scene, whether self-contact's supports act in the solve (SimulatorOptions::
  // self_contact_supports and the scene's bodies); every scene with self-contact has the collider.
  std::vector<char> solve_supports_;
  std::vector<int> unsettled_;  // the scenes whose event_unsettled is set, in the order changed
  BatchStepReport report_;
  // A Simulator's batch of one (forSimulator): a refused step throws and leaves everything as it
  // was (a batch's refused scene turns inactive while the batch's time goes on), and messages
  // are the whole scene's, without a batch's "<call>: scene 0: ".
  bool as_simulator_ = false;
};

// The public class (include/stabint/batch.hpp) is a pointer to this.
struct BatchSimulator::Impl : BatchDriver {
  using BatchDriver::BatchDriver;
};

}  // namespace stabint
