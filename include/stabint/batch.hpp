#pragma once
/// @file
/// Many independent scenes stepped as one (docs/method.md, "Batches"; the design:
/// docs/batch_design.md): parameter sweeps, training data, crowds of small objects.
#include <stabint/errors.hpp>
#include <stabint/scene.hpp>
#include <stabint/simulator.hpp>

#include <Eigen/Core>

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace stabint {

/// What BatchSimulator::step reports: every scene's step report and refusal.
struct BatchStepReport {
  /// One per scene, as that scene's own Simulator::step would report it, except
  /// energy_evaluations: the batched passes the scene took part in (the forcing's two whenever
  /// any scene's forcing changes during the step). A refused or inactive scene's report
  /// describes its kept state (its step count and time, energies, target).
  std::vector<StepReport> scenes;
  /// Per scene: empty when the scene stepped, else why its step was refused (the message its own
  /// Simulator::step would have thrown) or that it is inactive since a refused step.
  std::vector<std::string> refusals;
  /// Wall-clock seconds per phase of the whole batch's step. The scenes share every pass, so
  /// their own reports' `times` are zero (a batch of one's included: Simulator::step reports
  /// these as its own).
  PhaseTimes times;
};

/// A snapshot of every scene of a BatchSimulator (BatchSimulator::checkpoint()): the batch's
/// time and one Checkpoint per scene, each in Simulator's format. Restoring it into a batch of the
/// same scenes and options (BatchSimulator::restore(const BatchCheckpoint&)) continues bit for bit
/// as the batch did from that moment when the batch restored into has the same pins and element
/// stiffnesses as the checkpoint (the same batch, or a new one when no pin or element was changed
/// before the checkpoint): the batch's one factor is then the same, as a Simulator's is (see
/// Checkpoint). Otherwise the factor is updated rather than the same, and the run agrees to
/// round-off. A scene that was inactive (refused) is restored inactive. It records the batch's
/// options, and a batch of other options refuses it (restore names the option that differs). The
/// serialized form (bytes(), save()) is one file: a versioned header, the time, each scene's
/// checkpoint and the options (format version 2; a version 1 file has no options and restores
/// unchecked, as it did).
class BatchCheckpoint {
 public:
  /// The batch's time (BatchSimulator::time()) at the snapshot.
  double time() const { return time_; }
  /// The number of scenes.
  int size() const { return static_cast<int>(scenes_.size()); }
  /// Scene `scene`'s checkpoint (InvalidInputError out of range): it restores into a Simulator of
  /// that scene, as BatchSimulator::checkpoint(int) does.
  const Checkpoint& scene(int scene) const;
  /// The serialized form (what save() writes).
  std::string bytes() const;
  /// Checks the header, sizes, checksum and every scene's checkpoint; throws FileFormatError
  /// naming `origin` and the problem.
  static BatchCheckpoint fromBytes(const std::string& bytes, const std::string& origin = "batch checkpoint");
  /// Writes bytes() to a file; throws FileFormatError when it cannot be written completely.
  void save(const std::string& path) const;
  /// Reads a file written by save(); throws FileFormatError when missing or malformed.
  static BatchCheckpoint load(const std::string& path);

 private:
  friend class BatchSimulator;
  double time_ = 0.0;
  std::vector<Checkpoint> scenes_;
  // The options of the batch it was taken from that a restore compares, as (name, value) text;
  // none in a version 1 file (has_options_ false).
  std::vector<std::pair<std::string, std::string>> options_;
  bool has_options_ = false;
};

/// Steps many scenes with one integrator and one set of options: one local/global solve and one
/// block-diagonal factor for all (no element couples two scenes), and per scene its own energies,
/// target H*, blend decisions, forcing, damping and refusals, so that every scene follows the
/// trajectory its own Simulator would (to the round-off of the factor's ordering and, with
/// colliders, pin or element changes, of the updates of the one factor: docs/batch_design.md,
/// "Colliders" and "Per-scene input").
///
/// Colliders: each scene's colliders act on that scene's particles only, wherever the scenes lie
/// in space, with the scene's own collider motion (Collider::velocity, or setColliderPosition and
/// setColliderVelocity); its contact set, friction and final projection are its own Simulator's,
/// and what friction and the projection remove leaves that scene's H* only.
///
/// Per-frame input (docs/method.md, "Per-frame input"): every input call of Simulator (but
/// setPositions and setVelocities: setState; and setIterations: the options are the batch's), with
/// a leading `scene` argument and the scene's own indices (its particles, pins, colliders and
/// elements, numbered from 0 as in the scene passed in). Each has the semantics of Simulator's
/// call on that scene alone: ramps over the next step, events, the forcing rule, all booked in
/// that scene's H* only; pin and element changes update that scene's block of the one factor as
/// Simulator updates its own (rank updates, or a refactorization past a size). Bad input (a
/// scene or index out of range, a value Simulator refuses) is an InvalidInputError naming the
/// call, the scene and the field or index ("grab: scene 2: vertex 40 out of range ..."), and
/// changes nothing. A scene that is inactive after a refused step takes input as an active one
/// does: ramps follow the batch's time(), events are booked in its H*, and it acts on all of it
/// once setState reactivates it (so a sweep can, say, soften an exploded scene before restarting
/// it); the getters report values at the batch's time().
///
/// The batch's constraints (InvalidInputError, naming the scene where one is at fault): every
/// scene valid and with the same gravity, a backend that computes per-scene energies (the CPU
/// reference and OpenCL). Every solver option runs per scene, so that one scene's blow-up never
/// reaches the others: L-BFGS's (the default) dot products, line search and history, Chebyshev's
/// and Anderson's extrapolation and safeguard, Newton-CG's CG and line search are each scene's
/// own, and GlobalSolve::ConjugateGradient runs CG on each scene's block of the system on its own
/// (on the host, also on OpenCL: the device's CG sums over the whole system). The
/// stops by accuracy (tolerance, gradient_tolerance) are per scene: each scene stops its solve
/// where its own Simulator would and reports its own iterations. A batch of one
/// scene takes every option its Simulator takes and steps as that Simulator does, bit for bit on
/// the CPU reference (tests/test_batch_of_one.cpp).
class BatchSimulator {
 public:
  /// Validates and copies the scenes and options; a scene or option outside the constraints
  /// above is an InvalidInputError.
  BatchSimulator(const std::vector<Scene>& scenes, const SimulatorOptions& options);
  ~BatchSimulator();
  BatchSimulator(const BatchSimulator&) = delete;
  BatchSimulator& operator=(const BatchSimulator&) = delete;
  ///@{
  /// Movable, not copyable.
  BatchSimulator(BatchSimulator&&) noexcept;
  BatchSimulator& operator=(BatchSimulator&&) noexcept;
  ///@}

  /// Advances every active scene one step. Never throws for a scene that blows up or exceeds
  /// energy_limit: that scene's step is refused (BatchStepReport::refusals), its state kept, and
  /// it stays inactive (it takes no part in the solves and costs no solver work) until setState;
  /// the others step on. Within a step each solve serves only the scenes that need it (the
  /// blend's partner, the scenes whose solve has stopped by accuracy are skipped).
  const BatchStepReport& step();

  int size() const;  ///< number of scenes
  /// False after a refused step of the scene, until setState.
  bool active(int scene) const;
  ///@{
  /// Scene `scene`'s state (`n_s by 3`, a copy of its rows of allPositions()).
  Eigen::MatrixX3d positions(int scene) const;
  Eigen::MatrixX3d velocities(int scene) const;
  ///@}
  /// Every scene's positions, one after another (for renderers): scene s's rows start at
  /// firstParticle(s).
  const Eigen::MatrixX3d& allPositions() const;
  /// The first row of scene `scene` in allPositions().
  int firstParticle(int scene) const;
  /// The number of particles (rows) of scene `scene`.
  int numParticles(int scene) const;
  ///@{
  /// The batch's time (every active scene's), and a scene's (that of its last accepted state).
  double time() const;
  double time(int scene) const;
  ///@}
  /// The scene's step count (that of its last accepted state).
  int stepCount(int scene) const;
  double target(int scene) const;        ///< H* of the scene
  EnergyReport energy(int scene) const;  ///< of its current state
  double energyScale(int scene) const;   ///< its E_scale (of the scene alone)
  /// The options the batch was built with.
  const SimulatorOptions& options() const;
  /// The backend in words, as Simulator::backendDescription.
  std::string backendDescription() const;

  /// Replaces scene `scene`'s positions and velocities (`n_s by 3`, finite), as
  /// Simulator::setState: a discontinuous event booked in that scene's H* only (the next
  /// report's event_energy). A scene refused earlier steps again, from the batch's time.
  /// With BDF2 only in a batch of one, which restarts with a BE step as Simulator does (the scenes
  /// of a larger batch share one history, which the restart would drop for all). Bad input:
  /// InvalidInputError naming the scene, nothing changed.
  void setState(int scene, const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities);
  /// setState of several scenes at once (`scenes[i]` takes `positions[i]` and `velocities[i]`;
  /// each scene at most once): the same events, booked in the same order, bit for bit the calls
  /// one by one, but with one write of the rows and one pass with one wait for the potentials,
  /// where a device backend waits once per call (docs/guide.md, "Many scenes at once").
  /// Everything is checked first: bad input is an InvalidInputError naming the call, the scene
  /// and the field, and no scene changes.
  void setStates(const std::vector<int>& scenes, const std::vector<Eigen::MatrixX3d>& positions,
                 const std::vector<Eigen::MatrixX3d>& velocities);
  /// Local/global iteration budget of every later step of every scene (>= 1; the scenes share
  /// their solves); time, states and targets are kept, options().iterations follows.
  /// InvalidInputError otherwise, nothing changed.
  void setIterations(int iterations);
  /// Pin `pin` of scene `scene` (its index in that scene's list, grabbed pins included) moves its
  /// target linearly to `target` over the next step and stays there, as Simulator::setPinTarget:
  /// the work is booked by the forcing rule in that scene's H* only.
  void setPinTarget(int scene, int pin, const Eigen::Vector3d& target);
  /// Current target of a pin of scene `scene`, as Simulator::pinTarget.
  Eigen::Vector3d pinTarget(int scene, int pin) const;
  /// Scene `scene`'s per-particle external forces (`n_s by 3`), as Simulator::setExternalForces:
  /// ramped over the next step, persisting until the next call, booked by the forcing rule in that
  /// scene's H* only. The batch keeps one ramp for all particles, so another scene's forces, when
  /// set in the same frame, are evaluated within the step as `(1 - s) f + s f`: equal to its
  /// own Simulator's to round-off, not bit for bit.
  void setExternalForces(int scene, const Eigen::MatrixX3d& forces);
  /// Collider `collider` of scene `scene` (its index in that scene's list) translates to
  /// `position` over the next step, as Simulator::setColliderPosition.
  void setColliderPosition(int scene, int collider, const Eigen::Vector3d& position);
  /// Collider `collider` of scene `scene` moves on with `velocity`, as
  /// Simulator::setColliderVelocity.
  void setColliderVelocity(int scene, int collider, const Eigen::Vector3d& velocity);
  /// Where collider `collider` of scene `scene` is at time() and its velocity, as
  /// Simulator::colliderPosition and Simulator::colliderVelocity.
  ///@{
  Eigen::Vector3d colliderPosition(int scene, int collider) const;
  Eigen::Vector3d colliderVelocity(int scene, int collider) const;
  ///@}

  /// Attaches a handle to particle `vertex` of scene `scene`, as Simulator::grab: a new pin,
  /// returned as its index in that scene's pins (the scene's last; the later scenes' pins keep
  /// their own indices). The factor's block of that scene gets the rank-1 update.
  int grab(int scene, int vertex, double stiffness);
  /// Detaches pin `pin` of scene `scene`, as Simulator::release: an event of that scene.
  void release(int scene, int pin);
  /// Element `index` (or `indices`) of `kind` of scene `scene` (its index in that scene's list)
  /// gets `stiffness`, as Simulator::setElementStiffness: an event of that scene, its block of
  /// the factor updated. Its event is booked when first needed (the step, energy(), target(), a
  /// checkpoint, ...), so the changes of many scenes before a step share one energy pass and,
  /// on a device, one wait.
  ///@{
  void setElementStiffness(int scene, ElementKind kind, int index, double stiffness);
  void setElementStiffness(int scene, ElementKind kind, const std::vector<int>& indices, double stiffness);
  ///@}
  /// Disables or enables elements of scene `scene`, as Simulator::setElementEnabled.
  ///@{
  void setElementEnabled(int scene, ElementKind kind, int index, bool enabled);
  void setElementEnabled(int scene, ElementKind kind, const std::vector<int>& indices, bool enabled);
  ///@}
  /// Whether element `index` of `kind` of scene `scene` is enabled.
  bool elementEnabled(int scene, ElementKind kind, int index) const;

  /// Snapshot of scene `scene`, in Simulator's format: it restores into a Simulator of that scene
  /// (same options and backend), which continues as the scene did (to the round-off of the
  /// batch's factor against its own), and into scene `scene` of a batch of the same scenes
  /// (restore(int, const Checkpoint&)). Its time is the scene's (time(int)). A scene inactive
  /// after a refused step gives its kept state, at its own time, without BDF2 history (a restore
  /// into a Simulator restarts BDF2 with a BE step, as after setState).
  Checkpoint checkpoint(int scene) const;
  /// Continues scene `scene` from `checkpoint`: a snapshot of that scene (checkpoint(int), or a
  /// Simulator's of the same scene and options). The scenes share the batch's time, so the
  /// checkpoint's time must be time(), the batch's: its time-dependent forcing (pin laws and
  /// ramps, force fields, collider motion) continues from there, and it cannot be moved to another
  /// time. A scene inactive after a refused step becomes active again. The other scenes keep
  /// their state, targets and forcing; where the checkpoint's pins, element stiffnesses or
  /// enabled flags differ from the scene's, the scene's block of the factor is updated as grab
  /// and setElementStiffness update it (or the batch is refactored past a size; where its contact
  /// set differs, the batch's factor is assembled and refactored), so the other scenes continue
  /// to round-off. With BDF2 the checkpoint must have history when the batch has (and not when it
  /// has not): the batch keeps one. Refused, with nothing changed, by an InvalidInputError naming
  /// the call and the scene: a scene out of range, a checkpoint of another scene (particles,
  /// masses, rest shape, colliders, element counts), of another time, or of another history.
  void restore(int scene, const Checkpoint& checkpoint);
  /// Snapshot of every scene (see BatchCheckpoint).
  BatchCheckpoint checkpoint() const;
  /// Continues every scene from `checkpoint`, a snapshot of a batch of the same scenes (in the
  /// same order) and options: the batch's time, each scene's state, target, pins, elements,
  /// forcing and contact set, BDF2's history, which scenes are inactive. Refused, with nothing
  /// changed, by an InvalidInputError: other options (naming the first that differs; every option
  /// is compared but `iterations`, which setIterations changes at run time, and where the work runs,
  /// `backend` and `opencl`: a checkpoint moves between devices as a Simulator's does), another
  /// number of scenes, or a scene's checkpoint of another scene or of a time after the batch
  /// checkpoint's (naming the scene).
  void restore(const BatchCheckpoint& checkpoint);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace stabint
