#pragma once
/// @file
/// The stepping API: build a Simulator from a Scene and options, call step() once per frame.
#include <stabint/errors.hpp>
#include <stabint/reporters.hpp>
#include <stabint/scene.hpp>
#include <stabint/types.hpp>

#include <memory>
#include <string>
#include <vector>

namespace stabint {

/// A snapshot of a running simulation: time, step count, state, BDF2 history, the tracked
/// target H*, the pins (with grabbed and released handles), every element's stiffness and
/// enabled flag, and the forcing set by per-frame input (pin targets, external forces, collider motion). Restoring it
/// into a Simulator
/// of the same scene continues bit for bit as the original did from that moment (same options, same backend and
/// precision) when both have the same pins and element stiffnesses; when they differ (a checkpoint
/// taken during a grab or after a stiffness change, restored into a fresh simulator) the global
/// factors are updated rather than the same, and the run agrees to round-off. Options are not part of it. The
/// serialized form (bytes(), save()) is a versioned binary format of this library version and this machine's byte
/// order.
class Checkpoint {
 public:
  /// The simulation time of the snapshot.
  double time() const { return time_; }
  /// The step count of the snapshot.
  int stepCount() const { return step_count_; }
  /// The serialized form (what save() writes).
  const std::string& bytes() const { return bytes_; }
  /// Checks the header and sizes; throws FileFormatError naming `origin` and the problem.
  static Checkpoint fromBytes(std::string bytes, const std::string& origin = "checkpoint");
  /// Writes bytes() to a file; throws FileFormatError when it cannot be written completely.
  void save(const std::string& path) const;
  /// Reads a file written by save(); throws FileFormatError when missing or malformed.
  static Checkpoint load(const std::string& path);

 private:
  friend class BatchDriver;  // the library's one stepping driver writes every checkpoint
  std::string bytes_;
  double time_ = 0.0;
  int step_count_ = 0;
};

/// Steps a scene with one integrator. The scene is validated and copied at construction; the
/// caller's scene is never modified. One thread at a time: the const getters may finish work
/// the input calls left for them (an element change's event is booked when first read).
class Simulator {
 public:
  /// Throws InvalidInputError for a bad scene or options (also for masses too small for the
  /// stiffnesses at this time step: the implicit integrators' systems are factored here),
  /// OpenCLError subtypes for OpenCL problems (NoOpenCLDeviceError when no device matches).
  Simulator(const Scene& scene, const SimulatorOptions& options);
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;
  /// Movable (e.g. into a std::vector); a moved-from Simulator may only be destroyed or
  /// assigned to.
  ///@{
  Simulator(Simulator&&) noexcept;
  Simulator& operator=(Simulator&&) noexcept;
  ///@}

  /// Advances one time step. Throws NonFiniteStateError (state unchanged) when the step would
  /// produce a non-finite position or velocity, and its subtype EnergyLimitError when the step
  /// would exceed SimulatorOptions::energy_limit. After an accepted step it calls the reporters
  /// that are due (stabint/reporters.hpp); one that throws leaves the step accepted and makes
  /// step() throw ReporterError.
  const StepReport& step();

  /// Attaches a reporter, called after every accepted step it is due for, after the reporters
  /// attached before it. Throws InvalidInputError for a null reporter or one already attached.
  void addReporter(std::shared_ptr<Reporter> reporter);
  /// Detaches `reporter`; false when it was not attached.
  bool removeReporter(const std::shared_ptr<Reporter>& reporter);
  /// Detaches every reporter.
  void clearReporters();
  /// The attached reporters, in the order they are called.
  const std::vector<std::shared_ptr<Reporter>>& reporters() const;

  ///@{
  /// The current state, `n by 3`.
  const Eigen::MatrixX3d& positions() const;
  const Eigen::MatrixX3d& velocities() const;
  ///@}
  /// The simulation time of the current state.
  double time() const;
  /// Steps taken (refused steps not counted).
  int stepCount() const;
  double target() const;        ///< H*
  EnergyReport energy() const;  ///< of the current state
  double energyScale() const;   ///< E_scale used by the blend tolerance
  /// The simulator's copy of the scene (element stiffnesses as last set).
  const Scene& scene() const;
  /// The options it was built with (iterations as last set by setIterations).
  const SimulatorOptions& options() const;
  /// Report of the last completed step (default report before the first step).
  const StepReport& lastReport() const;
  /// Human-readable description of the backend and device in use.
  std::string backendDescription() const;

  // ---- per-frame input (docs/method.md, "Per-frame input") --------------------------------------
  // Every call validates its arguments first and throws InvalidInputError naming the problem
  // without changing anything. The energy each one puts in is booked in H*, so the blend never
  // undoes it.

  /// Pin `pin`'s target moves linearly from its current value to `target` over the next step and
  /// stays there (its scripted law, if any, is no longer used). Call it every frame with the
  /// hand's position to drag; the work is booked by the forcing rule, like a scripted pin.
  void setPinTarget(int pin, const Eigen::Vector3d& target);
  /// Current target of a pin (its law's or the last set one's value at time()).
  Eigen::Vector3d pinTarget(int pin) const;
  /// Per-particle external forces (`n by 3`, newtons, added to gravity and force fields): they
  /// move linearly from their current value to `forces` over the next step and persist until
  /// the next call (set zeros to remove them). Booked by the forcing rule.
  void setExternalForces(const Eigen::MatrixX3d& forces);
  /// Replaces positions and/or velocities (teleport, reset; `n by 3`, finite). A discontinuous
  /// event: H* moves by the jump of H it causes (reported in the next step's event_energy), and
  /// BDF2 restarts from this state, as a fresh simulator would.
  void setState(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities);
  /// As setState, replacing the positions only.
  void setPositions(const Eigen::MatrixX3d& positions);
  /// As setState, replacing the velocities only.
  void setVelocities(const Eigen::MatrixX3d& velocities);
  /// Collider `collider` (its index in the scene's list) translates linearly from where it is to
  /// `position` over the next step and stays there (its scene velocity is no longer used).
  /// `position` is where its reference point, Collider::center, goes (a plane's point, a sphere's
  /// or box's center, a capsule's first end; the rest of its shape moves with it). Call it every
  /// frame with a tool's or the mouse's position to push things around: the collider's work is
  /// booked by the forcing rule, like a dragged pin's, and friction drags along at the collider's
  /// velocity over the step. Finite, at most 1e150 in magnitude.
  void setColliderPosition(int collider, const Eigen::Vector3d& position);
  /// Collider `collider` translates with `velocity` (m/s; zeros stop it) from where it is now
  /// on, until the next setColliderPosition or setColliderVelocity. Booked as above.
  void setColliderVelocity(int collider, const Eigen::Vector3d& velocity);
  /// Where collider `collider`'s reference point (Collider::center) is at time(), and its
  /// velocity over the last step (its set or scene velocity when it moves on by one).
  ///@{
  Eigen::Vector3d colliderPosition(int collider) const;
  Eigen::Vector3d colliderVelocity(int collider) const;
  ///@}
  /// Local/global iteration budget of every later step (>= 1); time, state and H* are kept.
  void setIterations(int iterations);

  /// Attaches a handle to particle `vertex`: a new pin of `stiffness` (> 0, at most 1e150) whose
  /// target is the particle's current position (no energy jump), returned as its pin index for
  /// setPinTarget and release. The global matrix gains the pin's term by a rank-1 update of its
  /// factors (a stiffness more than 1e6 times the particle's diagonal refactors instead).
  int grab(int vertex, double stiffness);
  /// Detaches pin `pin` (a handle or a scene pin): its stiffness becomes 0 and its index stays
  /// valid (it can be grabbed again only through grab). A discontinuous event: the pin's energy
  /// leaves H and H* alike (event_energy); the factors get a rank-1 downdate. Releasing a pin that
  /// is already released (stiffness 0) is an InvalidInputError.
  void release(int pin);

  /// Element `index` of `kind` (its index in the scene's list of that kind; pins include grabbed
  /// ones) gets `stiffness` (finite, >= 0), in the same units as the scene's. A disabled element
  /// keeps the new stiffness for when it is enabled again. A discontinuous event: the element's
  /// energy jump enters H and H* alike (event_energy); the global matrix changes by the element's
  /// term, a rank-R update or downdate of the factors (R = rows of its A_e: 1 for springs, hinges
  /// and pins, 2 for triangle strain, 3 for tets). Time, state, BDF2 history and H* are kept.
  /// scene() shows the new stiffness. The list form changes several elements at once (all
  /// validated before any changes). The event is booked when something first needs it (step(),
  /// energy(), target(), checkpoint(), setState(), grab(), release() or the next change), with
  /// the same value as at once; in a batch the changes of many scenes so share one pass.
  ///@{
  void setElementStiffness(ElementKind kind, int index, double stiffness);
  void setElementStiffness(ElementKind kind, const std::vector<int>& indices, double stiffness);
  ///@}
  /// Disables (weight 0: the element exerts no force and has no energy) or enables an element,
  /// keeping its stiffness; booked and applied as setElementStiffness. A released pin has
  /// stiffness 0, so enabling it does nothing (grab again instead).
  ///@{
  void setElementEnabled(ElementKind kind, int index, bool enabled);
  void setElementEnabled(ElementKind kind, const std::vector<int>& indices, bool enabled);
  ///@}
  /// Whether element `index` of `kind` is enabled.
  bool elementEnabled(ElementKind kind, int index) const;

  /// Snapshot of the current simulation (see Checkpoint).
  Checkpoint checkpoint() const;
  /// Continues from a snapshot of a Simulator of the same scene. Throws InvalidInputError, its
  /// message starting "restore: ", when it belongs to another scene (particle, pin or element
  /// counts, masses or rest shape differ) or its system does not factor; a refused restore changes
  /// nothing, the global factors included: the simulator steps on bit for bit as it would have.
  void restore(const Checkpoint& checkpoint);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace stabint
