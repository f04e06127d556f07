#pragma once
// Shared pieces of stabint-study: the study's scenes, a recorded simulation run, the metrics
// computed from it, the cached reference trajectory and the subcommands.
#include <stabint/stabint.hpp>

#include <functional>
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
};

// ---- scenes --------------------------------------------------------------------------------

/// A scene of the study with its canonical parameter text (the cache key of its reference).
struct StudyScene {
  std::string key;     // "chain", "cloth", "tetbar"
  std::string params;  // every parameter that changes the trajectory, as text
  Scene scene;
  int grid_nx = 0, grid_ny = 0;  // cloth grid dimensions (row-major j*nx + i), 0 otherwise
  int free_end_first = -1;       // tet bar: particles of the free end x = length are
  int free_end_stride = 0;       // free_end_first + k*free_end_stride, k < free_end_count
  int free_end_count = 0;
  /// Where the static-equilibrium search starts (empty: the initial positions). Local/global
  /// descent from a pose far from equilibrium can take minutes (the tilted cloth swinging down
  /// through 120 degrees); from a pose near it, milliseconds.
  Eigen::MatrixX3d equilibrium_start;
};

/// makeChainPendulum() with the given spring stiffness (default scene: 1e4 N/m).
StudyScene chainScene(double stiffness = 1e4);
/// makeClothGrid 20x20 pinned at the two corners of its top edge, tilted 30 degrees below the
/// horizontal about that edge so it falls, swings and folds (see study_scenes.cpp for why).
StudyScene clothScene();
/// makeTetBar 8x2x2 (1 m x 0.25 m x 0.25 m), pinned at x = 0, with the given tet stiffness.
StudyScene tetBarScene(double stiffness = 1e5);

/// Potential energy E_int + U_ext of the static equilibrium the scene settles into, found by
/// converged backward-Euler steps with a huge step (inertia term c = 1/h^2 nearly zero): each
/// step is a descent on the potential from the previous state.
double equilibriumPotential(const Scene& scene, const Eigen::MatrixX3d& start = {});

/// Available energy of an unforced, undamped scene released from its initial state:
/// H_0 - (equilibrium potential). All energy metrics of the study are relative to it.
double availableEnergy(const StudyScene& scene);

// ---- a recorded run ------------------------------------------------------------------------

struct RunSpec {
  Integrator integrator = Integrator::EnergyBlend;
  double frame_step = 1.0 / 30.0;
  int substeps = 1;          // simulator steps per frame (h = frame_step / substeps)
  int iterations = 10;
  double tolerance = 0.0;    // > 0: iterate to this relative objective change (reference runs)
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
  double target = 0.0;  // H*
  BlendBranch branch = BlendBranch::None;  // of the frame's last step
  double alpha = 0.0;
  int iterations = 0;   // all solves of all substeps of the frame
  double total() const { return kinetic + elastic + external; }
};

struct RunResult {
  std::vector<FrameSample> samples;                // [0] is the initial state
  std::vector<Eigen::MatrixX3d> positions;         // per sample when recorded
  int blew_up_frame = -1;      // frame (1-based) whose step threw NonFiniteStateError
  bool stopped_early = false;  // stop_factor exceeded
  std::string blow_up_message;
  double seconds = 0.0;        // wall clock of all step() calls, the refused one included
  int frames_done = 0;
  long steps_tried = 0;        // step() calls, the refused one included
  int branch_im = 0, branch_be = 0, branch_fe = 0;  // blend decisions over all steps
  double energy_scale = 0.0;   // Simulator::energyScale()
  int substeps = 1;
  /// Wall clock per frame from every step tried, so a run that blew up early still has a cost.
  double ms_per_frame() const { return steps_tried > 0 ? 1e3 * seconds * substeps / steps_tried : 0.0; }
};

/// Runs `spec.frames` frames; a NonFiniteStateError ends the run and is recorded as the blow-up.
/// `on_frame(frame, simulator)` is called after each completed frame (frame >= 1).
RunResult simulate(const Scene& scene, const RunSpec& spec,
                   const std::function<void(int, const stabint::Simulator&)>& on_frame = {});

// ---- metrics -------------------------------------------------------------------------------

struct Metrics {
  double h0 = 0.0, h_end = 0.0, h_min = 0.0, h_max = 0.0;
  double available = 0.0;       // E_avail of the scene
  double max_target_dev = 0.0;  // max |H - H*| / E_avail
  double max_rise = 0.0;        // max (H - H_0) / E_avail
  double drift = 0.0;           // (H_end - H_0) / E_avail
  double damping = 0.0;         // (H_0 - mean H over the last 10 % of frames) / E_avail
  std::string verdict;          // "stable", "over-damped", "exploded"
};
/// Verdict thresholds: exploded when the run blew up or max |H - H_0| > kExplodeFactor E_avail;
/// over-damped when it lost more than kOverDampedFraction of E_avail; stable otherwise.
constexpr double kExplodeFactor = 10.0;
constexpr double kOverDampedFraction = 0.5;
Metrics energyMetrics(const RunResult& run, double available_energy);

/// RMS over particles and frames 1..N of |x - x_ref|; frames the run did not reach count as
/// missing: the result is +inf when the run blew up before the reference horizon.
double positionRmsError(const RunResult& run, const std::vector<Eigen::MatrixX3d>& reference);

// ---- reference -----------------------------------------------------------------------------

struct Reference {
  std::vector<Eigen::MatrixX3d> positions;  // frames 0..N
  std::vector<double> energy;               // H per frame
  int substeps = 0;
  double self_error = 0.0;   // RMS |x_ref(h/s) - x_ref(h/(s/2))|: an upper estimate of its error
  double max_energy_dev = 0.0;  // max |H - H_0| / E_avail
  bool from_cache = false;
};
constexpr int kReferenceFrames = 60;     // 2 s at 30 frames per second
constexpr int kReferenceSubsteps = 16;   // reference step h/16
/// Implicit midpoint with h/16 and local/global iterations to a 1e-10 relative objective change,
/// sampled at frame times; cached in <out>/cache/<scene>-<hash>.bin.
Reference loadOrComputeReference(const StudyScene& scene, const StudyOptions& options);

// ---- subcommands ---------------------------------------------------------------------------

void runTable(const StudyOptions& options);
void runReference(const StudyOptions& options);
void runSweep(const StudyOptions& options);
void runStability(const StudyOptions& options);
void runEnergy(const StudyOptions& options);
void runCrosscheck(const StudyOptions& options);

// ---- small helpers -------------------------------------------------------------------------

/// Creates the directory (and parents) if needed.
void ensureDirectory(const std::string& path);
std::string joinPath(const std::string& dir, const std::string& name);
/// Prints a line prefixed with the elapsed time since program start, flushed.
void progress(const std::string& message);

}  // namespace study
