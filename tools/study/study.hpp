#pragma once
// Shared pieces of stabint-study: the study's scenes, a recorded simulation run, the metrics
// computed from it, the cached reference trajectory and the subcommands.
#include <stabint/stabint.hpp>

#include <Eigen/Geometry>  // cross products (angular momentum, spinning scenes)

#include <array>
#include <functional>
#include <limits>
#include <map>
#include <iosfwd>
#include <string>
#include <vector>

namespace study {

using stabint::BackendKind;
using stabint::BlendBranch;
using stabint::Integrator;
using stabint::Scene;

/// Settings shared by every subcommand (command-line options).
struct StudyOptions {
  std::string out = "results";
  BackendKind backend = BackendKind::CpuReference;
  bool quick = false;  // smoke-test sizes: fewer frames and cells; never for reported numbers
  std::string mesh;    // drop, fold: the TetGen mesh (BASE, BASE.node or BASE.ele)
};

// ---- scenes --------------------------------------------------------------------------------

/// A scene of the study with its canonical parameter text (the cache key of its reference).
struct StudyScene {
  std::string key;     // "chain", "cloth", "tetbar"
  std::string params;  // every parameter that changes the trajectory, as text (colliders aside)
  Scene scene;
  int grid_nx = 0, grid_ny = 0;  // cloth grid dimensions (row-major j*nx + i), 0 otherwise
  int free_end_first = -1;       // tet bar: particles of the free end x = length are
  int free_end_stride = 0;       // free_end_first + k*free_end_stride, k < free_end_count
  int free_end_count = 0;
  /// Where the static-equilibrium search starts (empty: the initial positions). Local/global
  /// descent from a pose far from equilibrium can take minutes (the tilted cloth swinging down
  /// through 120 degrees); from a pose near it, milliseconds.
  Eigen::MatrixX3d equilibrium_start;
  /// The real-time frame step the study runs this scene at (one simulator step per frame).
  double frame_step = 1.0 / 30.0;
  /// The small-step motion reference (motion_reference.cpp): integrator, steps per frame,
  /// solve tolerance (implicit references only) and horizon. Chosen per scene so that its energy
  /// error stays below 3e-4 E_avail and two step counts agree (the checks it reports).
  Integrator reference_integrator = Integrator::SymplecticEuler;
  int reference_substeps = 2000;
  double reference_tolerance = 0.0;
  double reference_seconds = 10.0;
  /// A scene driven from rest (E_avail about 0): its energy unit is instead the most energy the
  /// reference holds above its static equilibrium over the run, what the drive puts in.
  bool driven_energy_unit = false;
};

/// makeChainPendulum() with the given spring stiffness (default scene: 1e4 N/m).
StudyScene chainScene(double stiffness = 1e4);
/// makeClothGrid 20x20 pinned at the two corners of its top edge, tilted 30 degrees below the
/// horizontal about that edge so it falls, swings and folds (see study_scenes.cpp for why).
/// The default stretch stiffness (1e3 N/m) is the main job's cloth (key "cloth"); any other is
/// the stiff cloth of issue 8 (key "cloth_stiff", run at h = 1/15).
StudyScene clothScene(double stretch_stiffness = 1e3);
constexpr double kStiffClothStretch = 1e6;
/// The handle cloth's handle frequency in scenes/cloth_handle.json [Hz].
constexpr double kHandleFrequency = 0.5;
/// The handle frequencies of the motion command's response curve (handle_response.csv) [Hz].
constexpr std::array<double, 5> kHandleFrequencies = {0.3, 0.4, kHandleFrequency, 0.6, 0.8};
/// The same tilted cloth as clothScene, n x n, built from triangle strain and bending hinges
/// instead of springs (ClothModel::Triangles; key "cloth_triangles" for n = 20).
/// `strain_min` < 1 lets the membrane compress freely down to it (cloth buckles rather than
/// resisting compression).
StudyScene triangleClothScene(int n = 20, double strain_stiffness = 1e3, double strain_min = 1.0);
constexpr double kTriangleClothHinge = 1e-4;  // J: bending hinge stiffness of the study's triangle cloths
/// scenes/cloth_handle.json: a cloth on a swinging handle in a gusty wind, with damping; the
/// handle swings at `frequency` Hz (the file's 0.5 Hz keeps the key "handle"; any other is
/// "handle_<frequency>Hz").
StudyScene handleClothScene(double frequency = kHandleFrequency);
/// scenes/cloth_stiff_drag.json (key "stiff_drag"): a stiff triangle cloth on its two top corners
/// whose bottom corner a hand moves along a path that stretches it, so that it flails.
StudyScene stiffDragScene();
/// The tet bar with no pins and no gravity, spinning rigidly at `omega` rad/s about an axis
/// through its centre of mass. `general`: about the axis (1, 2, 3)/|.| (not a principal axis)
/// and stretched by 20 % along its length; else about y (end over end), at its rest shape.
StudyScene spinningBarScene(bool general, double omega = 6.0);
/// One 1 kg particle on a pin of stiffness k whose target moves as 0.3 m sin(2 pi 2 Hz t) along
/// x; no gravity. Linear: implicit midpoint is exact in one iteration.
StudyScene movingPinScene(double stiffness);
constexpr double kMovingPinAmplitude = 0.3;  // m
constexpr double kMovingPinFrequency = 2.0;  // Hz
/// makeTetBar 8x2x2 (1 m x 0.25 m x 0.25 m), pinned at x = 0, with the given tet stiffness.
StudyScene tetBarScene(double stiffness = 1e5);

/// Potential energy E_int + U_ext of the static equilibrium the scene settles into, found by
/// converged backward-Euler steps with a huge step (inertia term c = 1/h^2 nearly zero): each
/// step is a descent on the potential from the previous state.
double equilibriumPotential(const Scene& scene, const Eigen::MatrixX3d& start = {});

/// Available energy of an unforced, undamped scene released from its initial state:
/// H_0 - (equilibrium potential). All energy metrics of the study are relative to it.
double availableEnergy(const StudyScene& scene);

/// The text that keys a cached reference of `scene`: its params and every field of its
/// colliders (none: params alone, so the keys of collider-free scenes are unchanged).
std::string cacheDescription(const StudyScene& scene);

// ---- a recorded run ------------------------------------------------------------------------

struct RunSpec {
  Integrator integrator = Integrator::EnergyBlend;
  stabint::Acceleration acceleration = stabint::SimulatorOptions{}.acceleration;  // the default solver
  double frame_step = 1.0 / 30.0;
  int substeps = 1;  // simulator steps per frame (h = frame_step / substeps)
  int iterations = 10;
  double tolerance = 0.0;  // > 0: iterate to this relative objective change (reference runs)
  int max_iterations = 1000;
  int be_iterations = stabint::SimulatorOptions{}.be_iterations;  // the blend's BE partner budget
  int frames = 300;
  BackendKind backend = BackendKind::CpuReference;
  bool record_positions = false;
  /// Stop early once |H - H_0| exceeds this many times `energy_unit` (0: never stop early).
  double stop_factor = 0.0;
  double energy_unit = 0.0;
};

struct FrameSample {
  double time = 0.0;
  double kinetic = 0.0, elastic = 0.0, external = 0.0;
  double target = 0.0;                     // H*
  BlendBranch branch = BlendBranch::None;  // of the frame's last step
  double alpha = 0.0;
  int iterations = 0;    // all solves of all substeps of the frame
  double seconds = 0.0;  // wall clock of the frame's step() calls
  double total() const { return kinetic + elastic + external; }
};

struct RunResult {
  std::vector<FrameSample> samples;         // [0] is the initial state
  std::vector<Eigen::MatrixX3d> positions;  // per sample when recorded
  int blew_up_frame = -1;                   // frame (1-based) whose step threw NonFiniteStateError
  bool stopped_early = false;               // stop_factor exceeded
  std::string blow_up_message;
  double seconds = 0.0;  // wall clock of all step() calls, the refused one included
  int frames_done = 0;
  long steps_tried = 0;  // step() calls, the refused one included
  /// Blend decisions over all steps, keyed by blendBranchName() (no entry for "-").
  std::map<std::string, int> branches;
  /// Steps whose blend took its partner whole (alpha = 1): the target was out of the partner's
  /// reach, or the root find ended there.
  int partner_whole = 0;
  std::map<std::string, int> partner_whole_by_branch;  // the same, per branch name
  int branchCount(const std::string& name) const {
    const auto it = branches.find(name);
    return it == branches.end() ? 0 : it->second;
  }
  /// "IM=3;BE=196;FE=101": every branch taken, in name order (no commas: a CSV field).
  std::string branchSummary() const;
  /// The same for partner_whole_by_branch ("BE=244").
  std::string partnerWholeSummary() const;
  double energy_scale = 0.0;  // Simulator::energyScale()
  int substeps = 1;
  /// Wall clock per frame from every step tried, so a run that blew up early still has a cost.
  double ms_per_frame() const { return steps_tried > 0 ? 1e3 * seconds * substeps / steps_tried : 0.0; }
  /// Median over the completed frames of their wall clock: on a machine shared with other jobs
  /// the mean picks up every stall, the median does not (the sweep's equal-time comparisons use
  /// it). ms_per_frame() when no frame completed.
  double medianMsPerFrame() const;
};

/// Runs `spec.frames` frames; a NonFiniteStateError ends the run and is recorded as the blow-up.
/// `on_frame(frame, simulator)` is called after each completed frame (frame >= 1).
RunResult simulate(const Scene& scene, const RunSpec& spec,
                   const std::function<void(int, const stabint::Simulator&)>& on_frame = {});
/// The same runs for many scenes at once, one stabint::BatchSimulator for all (the options of
/// `spec`, which a batch must support: fixed iterations, plain or L-BFGS solves): each run is what
/// simulate(scenes[s], spec with energy_unit = energy_units[s]) records, to the round-off of the
/// batch's factor ordering, except the wall clock, which is the batch's divided evenly among its
/// scenes. A refused scene step is the run's blow-up; a stopped or blown-up scene is no longer
/// recorded, while the batch steps on until every scene stopped or `spec.frames` frames.
std::vector<RunResult> simulateBatch(const std::vector<Scene>& scenes, const RunSpec& spec,
                                     const std::vector<double>& energy_units);

// ---- metrics -------------------------------------------------------------------------------

struct Metrics {
  double h0 = 0.0, h_end = 0.0, h_min = 0.0, h_max = 0.0;
  double available = 0.0;       // E_avail of the scene
  double max_target_dev = 0.0;  // max |H - H*| / E_avail
  double max_rise = 0.0;        // max (H - H_0) / E_avail
  double drift = 0.0;           // (H_end - H_0) / E_avail
  double damping = 0.0;         // (H_0 - mean H over the last 10 % of frames) / E_avail
  /// Time [s] of the first frame with |H - H_0| > kExplodeFactor E_avail, or of the last finite
  /// frame before a blow-up; +inf when the run never exploded. Statistics over a window that
  /// ends before it (the trajectory error over 0-1 s of a run that explodes at 3 s) still mean
  /// something.
  double exploded_at = std::numeric_limits<double>::infinity();
  std::string verdict;  // "stable", "over-damped", "exploded"
};
/// Verdict thresholds: exploded when the run blew up or max |H - H_0| > kExplodeFactor E_avail;
/// over-damped when it lost more than kOverDampedFraction of E_avail; stable otherwise.
constexpr double kExplodeFactor = 10.0;
constexpr double kOverDampedFraction = 0.5;
Metrics energyMetrics(const RunResult& run, double available_energy);

/// RMS over particles and frames 1..N of |x - x_ref|; frames the run did not reach count as
/// missing: the result is +inf when the run blew up before the reference horizon.
double positionRmsError(const RunResult& run, const std::vector<Eigen::MatrixX3d>& reference);

// ---- motion metrics (issue 8): pure functions of recorded series, tested on synthetic data ---

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// RMS trajectory error sqrt(sum_{f=1..last_frame} sum_p |x_f,p - xref_f,p|^2 / (last_frame P)):
/// over particles and frames 1..last_frame (frame 0 is the shared initial state). +inf when the
/// run has fewer frames (it blew up) or a non-finite entry; NaN when the reference is too short.
double rmsTrajectoryError(const std::vector<Eigen::MatrixX3d>& run, const std::vector<Eigen::MatrixX3d>& reference,
                          int last_frame);
/// Mean of values[f] over the frames f whose time f*frame_step lies in [t0, t1] (1e-9 s slack);
/// NaN when the series does not reach t1.
double meanOverWindow(const std::vector<double>& values, double frame_step, double t0, double t1);
/// Frame-to-frame flicker of the kinetic energy: the median over consecutive frame pairs
/// (frames 1..N; frame 0 is the release from rest) of max(K_i+1/K_i, K_i/K_i+1), computed as
/// (max + floor)/(min + floor) so that two frames at rest count as 1, not 0/0. `floor` is a
/// negligible energy (the study uses 1e-9 E_avail). 1 for smooth motion, about 1.1 for the
/// reference cloth; a K that flips between two levels every frame gives their ratio. NaN when
/// fewer than two frames.
double kineticFlicker(const std::vector<double>& kinetic, double floor);
double median(std::vector<double> values);
/// Swing period [s] of a series sampled every `frame_step` (the height of the centre of mass):
/// the mean spacing of its minima, each the lowest sample within kSwingWindow frames on either
/// side (so frame-to-frame jitter is no minimum) and placed between samples by a parabola
/// through its two neighbours. NaN with fewer than three minima or a non-finite sample.
double swingPeriod(const std::vector<double>& series, double frame_step);
constexpr int kSwingWindow = 4;
/// Mass-weighted centre of mass of the rows of x.
Eigen::Vector3d centreOfMass(const Eigen::MatrixX3d& x, const Eigen::VectorXd& masses);
/// Angular momentum sum_p m_p (x_p - c) x v_p about the centre of mass c.
Eigen::Vector3d angularMomentum(const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v, const Eigen::VectorXd& masses);

/// The window of the mean-K statistic: 5-10 s (the cloth's swing has settled into its long-run
/// pattern); for a shorter horizon T (quick mode) the second half [T/2, T].
struct TimeWindow {
  double from = 0.0, to = 0.0;
};
TimeWindow kineticWindow(double horizon);
constexpr double kShortRmsSeconds = 0.5;  // RMS trajectory error over 0-0.5 s ...
constexpr double kLongRmsSeconds = 1.0;   // ... and 0-1 s, where the reference is sharp
/// Verdicts on motion: frozen when the mean K over the window is below kFrozenFraction of the
/// reference's; jittery when the flicker exceeds kJitteryFlicker.
constexpr double kFrozenFraction = 0.3;
constexpr double kJitteryFlicker = 1.5;
constexpr double kFlickerFloor = 1e-9;  // times E_avail

/// The combined verdict: "exploded" (energy verdict); else the flags that apply, joined by '+',
/// among "over-damped" (energy), "frozen", "jittery"; else "stable". A NaN statistic (no
/// reference over that window) raises no flag.
std::string combinedVerdict(const std::string& energy_verdict, double mean_k_ratio, double flicker);
// ---- reference -----------------------------------------------------------------------------

struct Reference {
  std::vector<Eigen::MatrixX3d> positions;  // frames 0..N
  std::vector<double> energy;               // H per frame
  int substeps = 0;
  double self_error = 0.0;      // RMS |x_ref(h/s) - x_ref(h/(s/2))|: an upper estimate of its error
  double max_energy_dev = 0.0;  // max |H - H_0| / E_avail
  bool from_cache = false;
};
constexpr int kReferenceFrames = 60;    // 2 s at 30 frames per second
constexpr int kReferenceSubsteps = 16;  // reference step h/16
/// Implicit midpoint with h/16 and local/global iterations to a 1e-10 relative objective change,
/// sampled at frame times; cached in <out>/cache/<scene>-<hash>.bin and kept in memory for the
/// rest of the run. Thread-safe.
const Reference& loadOrComputeReference(const StudyScene& scene, const StudyOptions& options);

// ---- motion reference ----------------------------------------------------------------------

/// A small-step reference run of a scene (StudyScene::reference_*), sampled at the scene's
/// frame times, with the checks of its sharpness.
struct MotionReference {
  std::string method;  // e.g. "SE h/2000"
  double frame_step = 0.0;
  std::vector<Eigen::MatrixX3d> positions;  // frames 0..N
  std::vector<double> kinetic, energy;      // K and H per frame
  double available = 0.0;                   // E_avail of the scene
  int substeps = 0, check_substeps = 0;     // the reference and its check run (half the steps)
  double energy_error = 0.0;                // max |H - H*| / E_avail (H* books forcing and damping exactly)
  double self_rms = 0.0;                    // RMS |x(substeps) - x(check_substeps)| over 0-1 s [m]
  double self_mean_k = 0.0;                 // mean K of the check run over the K window / the reference's
  double seconds = 0.0;                     // wall clock of both runs (0 when cached)
  bool from_cache = false;
  double horizon() const { return frame_step * static_cast<double>(positions.size() - 1); }
};
/// Computes (or reads from <out>/cache/) the scene's motion reference over its horizon
/// (StudyScene::reference_seconds; at most 1 s in --quick mode), on the CPU reference backend,
/// and keeps it in memory for the rest of the run. Thread-safe.
const MotionReference& motionReference(const StudyScene& scene, const StudyOptions& options);

/// Motion of one run against the scene's reference.
struct MotionMetrics {
  double rms_short = kNaN, rms_long = kNaN;  // RMS trajectory error over 0-0.5 s and 0-1 s [m]
  TimeWindow k_window;
  double mean_k = kNaN, mean_k_ref = kNaN, mean_k_ratio = kNaN;
  double flicker = kNaN, flicker_ref = kNaN;
  std::string verdict;  // combinedVerdict
};
/// `run` must have recorded positions for the trajectory errors; the K window is that of the
/// shorter of the run's planned horizon (`frames`) and the reference's.
MotionMetrics motionMetrics(const RunResult& run, int frames, const MotionReference& reference, const Metrics& energy);
std::vector<double> kineticSeries(const RunResult& run);

/// One run of a study scene judged on energy and motion: the run (positions recorded), its
/// energy metrics and its motion metrics against the scene's motion reference.
struct JudgedRun {
  RunResult run;
  Metrics energy;
  MotionMetrics motion;
};
/// Runs `spec` (frames, integrator, budget; the frame step and position recording are set here)
/// on `scene` and judges it against motionReference(scene).
JudgedRun judgedRun(const StudyScene& scene, RunSpec spec, const StudyOptions& options);
/// y of the centre of mass at frame f (positions recorded).
double comY(const RunResult& run, const Scene& scene, size_t frame);

// ---- subcommands ---------------------------------------------------------------------------

void runPrefetch(const StudyOptions& options);  // prefetch.cpp
void runTable(const StudyOptions& options);
void runReference(const StudyOptions& options);
void runSweep(const StudyOptions& options);
void runStability(const StudyOptions& options);
void runEnergy(const StudyOptions& options);
void runCrosscheck(const StudyOptions& options);
void runMotion(const StudyOptions& options);
void runTeaser(const StudyOptions& options);       // cmd_teaser.cpp
void runInteraction(const StudyOptions& options);  // cmd_interaction.cpp
void runContact(const StudyOptions& options);      // cmd_contact.cpp
void runDrop(const StudyOptions& options);         // cmd_drop.cpp (needs options.mesh; not in `all`)
void runFold(const StudyOptions& options);         // cmd_fold.cpp (needs options.mesh; not in `all`)

// ---- small helpers -------------------------------------------------------------------------

/// Creates the directory (and parents) if needed.
void ensureDirectory(const std::string& path);
std::string joinPath(const std::string& dir, const std::string& name);
/// Appends one frame of positions to a `<command>_<integrator>.bin` file: float32 little-endian,
/// particles x 3 (bench/povray_render.py's readers take frames x particles x 3).
void appendPositions(std::ofstream& out, const Eigen::MatrixX3d& x);
/// The TetGen mesh --mesh names (BASE, BASE.node or BASE.ele), loaded with `material`.
Scene loadTetGenMesh(const std::string& mesh, const stabint::SolidMaterial& material);
/// The label suffix of a series by its solver: "" for the library's default (L-BFGS), "+PD"
/// (plain Projective-Dynamics iterations), "+AA" (Anderson), "+LB" (L-BFGS), "+NT" (Newton-CG),
/// "+CH" (Chebyshev).
const char* accelerationSuffix(stabint::Acceleration acceleration);
/// Prints a line prefixed with the elapsed time since program start, flushed.
void progress(const std::string& message);

}  // namespace study
