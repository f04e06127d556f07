// `motion`: the scenes and measurements of issue 8's targets, every run judged on motion against
// the scene's small-step reference (motion_reference.cpp):
//   cloth        the main job's falling cloth, h = 1/30, 10 iterations, 10 s: trajectory error,
//                mean K over 5-10 s against the reference's, flicker of K, max |H - H*|;
//   chain        the stiff chain pendulum: max |H - H*| / E_avail and the same motion metrics;
//   spinbar      a free tet bar spinning at 6 rad/s (no pins, no gravity), about y and, stretched
//                by 20 %, about a general axis: angular momentum kept after 10 s;
//   moving_pin   one particle on a sinusoidally moving pin: max |H* - H_IM| (IM is exact there);
//   handle       scenes/cloth_handle.json: steps whose blend took its partner whole, mean K;
//   stiff_drag   scenes/cloth_stiff_drag.json: a hand drags a stiff cloth against its fixed corners,
//                which flails in the reference: mean K over 5-10 s, flicker;
//   cloth_stiff  the cloth with 1e6 N/m springs at h = 1/15: centre-of-mass drop within 1 s, flicker.
// Writes motion.csv (one row per scene and integrator), moving_pin.csv, motion_reference.csv,
// motion_series.csv (per frame: K, H, H*, y of the centre of mass; the references as integrator
// "reference") and prints the motion table.
#include "csv.hpp"
#include "study.hpp"

#include <cmath>
#include <cstdio>

namespace study {

namespace {

constexpr double kSpinSeconds = 10.0;
constexpr int kRealTimeSeconds = 10;  // every motion run: 10 s of real-time frames

int framesFor(const StudyScene& s, const StudyOptions& options, double seconds) {
  const double quick_seconds = std::min(seconds, 1.0);  // smoke-test sizes
  return static_cast<int>(std::lround((options.quick ? quick_seconds : seconds) / s.frame_step));
}

/// What the motion table shows per scene and integrator; NaN where it does not apply.
struct MotionRow {
  std::string scene, integrator;
  const JudgedRun* judged = nullptr;
  double com_drop = kNaN, com_drop_ref = kNaN;  // comDropWithinOneSecond [m]
  double period = kNaN, period_ref = kNaN;      // swingPeriod of the centre of mass's height [s]
  double l_kept = kNaN, l_error = kNaN;         // spinning bar: L.L0/|L0|^2 and |L - L0|/|L0|
  double energy_kept = kNaN;                    // spinning bar: H_end / H_0
};

class MotionTable {
 public:
  explicit MotionTable(const StudyOptions& options)
      : csv_(joinPath(options.out, "motion.csv"), {"scene",
                                                   "integrator",
                                                   "backend",
                                                   "h",
                                                   "iterations",
                                                   "frames",
                                                   "frames_done",
                                                   "ms_per_frame",
                                                   "ms_per_frame_median",
                                                   "exploded_at_s",
                                                   "E_avail",
                                                   "rms_0_0.5s_m",
                                                   "rms_0_1s_m",
                                                   "k_window_from_s",
                                                   "k_window_to_s",
                                                   "mean_K_J",
                                                   "mean_K_ref_J",
                                                   "mean_K_ratio",
                                                   "flicker",
                                                   "flicker_ref",
                                                   "max_dev_target_rel",
                                                   "com_drop_1s_m",
                                                   "com_drop_1s_ref_m",
                                                   "swing_period_s",
                                                   "swing_period_ref_s",
                                                   "L_kept",
                                                   "L_error",
                                                   "H_end_over_H0",
                                                   "partner_whole_steps",
                                                   "partner_whole_by_branch",
                                                   "steps",
                                                   "branches",
                                                   "blew_up_frame",
                                                   "energy_verdict",
                                                   "verdict"}),
        backend_(stabint::backendName(options.backend)) {
    std::printf(
        "\nMotion table (issue 8), backend %s: trajectory error against the small-step reference, mean K over\n"
        "the K window relative to the reference's, flicker = median over frames of max(K_i+1/K_i, K_i/K_i+1);\n"
        "frozen: mean K < %g x reference; jittery: flicker > %g.\n",
        backend_.c_str(), kFrozenFraction, kJitteryFlicker);
    std::printf("%-15s %-6s %7s %9s %9s %9s %7s %8s %9s %8s %7s %8s %7s %9s  %s\n", "scene", "integ", "ms/fr*",
                "rms0-.5s", "rms0-1s", "meanK", "K/Kref", "flicker", "max|H-H*|", "drop1s", "period", "L kept", "whole",
                "branches", "verdict");
  }

  /// The reference's own row: its mean K, flicker, energy error and centre-of-mass fall.
  void addReference(const StudyScene& s, const MotionReference& ref, double com_drop, double period) {
    const TimeWindow w = kineticWindow(ref.horizon());
    const double mean_k = meanOverWindow(ref.kinetic, ref.frame_step, w.from, w.to);
    const double flicker = kineticFlicker(ref.kinetic, kFlickerFloor * ref.available);
    csv_ << s.key << "reference"
         << "cpu" << ref.frame_step / ref.substeps << 0 << ref.positions.size() - 1 << ref.positions.size() - 1 << kNaN
         << kNaN << kNaN << ref.available << 0.0 << 0.0 << w.from << w.to << mean_k << mean_k << 1.0 << flicker
         << flicker << ref.energy_error << com_drop << com_drop << period << period << kNaN << kNaN << kNaN << 0 << "-"
         << 0 << "-" << -1 << "reference"
         << "reference";
    csv_.endRow();
    std::printf("%-15s %-6s %7s %9s %9s %9.3g %7s %8.3g %9.2g %8.3g %7.3f %8s %7s %9s  %s\n", s.key.c_str(), "ref", "-",
                "-", "-", mean_k, "1", flicker, ref.energy_error, com_drop, period, "-", "-", "-", ref.method.c_str());
  }

  void add(const MotionRow& r, double h, int iterations, int frames) {
    const RunResult& run = r.judged->run;
    const Metrics& e = r.judged->energy;
    const MotionMetrics& m = r.judged->motion;
    csv_ << r.scene << r.integrator << backend_ << h << iterations << frames << run.frames_done << run.ms_per_frame()
         << run.medianMsPerFrame() << e.exploded_at << e.available << m.rms_short << m.rms_long << m.k_window.from
         << m.k_window.to << m.mean_k << m.mean_k_ref << m.mean_k_ratio << m.flicker << m.flicker_ref
         << e.max_target_dev << r.com_drop << r.com_drop_ref << r.period << r.period_ref << r.l_kept << r.l_error
         << r.energy_kept << run.partner_whole << run.partnerWholeSummary() << run.steps_tried << run.branchSummary()
         << run.blew_up_frame << e.verdict << m.verdict;
    csv_.endRow();
    char whole[16] = "-";
    if (!run.branches.empty()) std::snprintf(whole, sizeof whole, "%d/%ld", run.partner_whole, run.steps_tried);
    std::printf("%-15s %-6s %7.3f %9.3g %9.3g %9.3g %7.3g %8.3g %9.3g %8.3g %7.3f %8.4g %7s %9s  %s\n", r.scene.c_str(),
                r.integrator.c_str(), run.medianMsPerFrame(), m.rms_short, m.rms_long, m.mean_k, m.mean_k_ratio,
                m.flicker, e.max_target_dev, r.com_drop, r.period, r.l_kept, whole, run.branchSummary().c_str(),
                m.verdict.c_str());
    std::fflush(stdout);
  }

 private:
  CsvWriter csv_;
  std::string backend_;
};

class SeriesWriter {
 public:
  explicit SeriesWriter(const StudyOptions& options)
      : csv_(joinPath(options.out, "motion_series.csv"),
             {"scene", "integrator", "frame", "time", "kinetic", "H", "H_target", "com_y"}) {}
  void add(const StudyScene& s, const std::string& integrator, const RunResult& run) {
    for (size_t f = 0; f < run.samples.size(); ++f) {
      const FrameSample& fs = run.samples[f];
      csv_ << s.key << integrator << f << fs.time << fs.kinetic << fs.total() << fs.target << comY(run, s.scene, f);
      csv_.endRow();
    }
  }
  void addReference(const StudyScene& s, const MotionReference& ref) {
    for (size_t f = 0; f < ref.positions.size(); ++f) {
      csv_ << s.key << "reference" << f << f * ref.frame_step << ref.kinetic[f] << ref.energy[f] << ref.energy[f]
           << centreOfMass(ref.positions[f], s.scene.masses).y();
      csv_.endRow();
    }
  }

 private:
  CsvWriter csv_;
};

// How far the centre of mass falls within the first second: max over frames t <= 1 s of
// y_com(0) - y_com(t). The largest drop, not the drop at 1 s: the stiff cloth falls 0.25 m in
// 0.45 s and has swung back up to -0.05 m at 1 s.
double comDropWithinOneSecond(const std::vector<Eigen::MatrixX3d>& positions, const Scene& scene, double h) {
  const size_t last = static_cast<size_t>(std::lround(1.0 / h));
  if (positions.size() <= last) return kNaN;
  const double y0 = centreOfMass(positions[0], scene.masses).y();
  double fall = 0.0;
  for (size_t f = 1; f <= last; ++f) fall = std::max(fall, y0 - centreOfMass(positions[f], scene.masses).y());
  return fall;
}

std::vector<double> comHeights(const std::vector<Eigen::MatrixX3d>& positions, const Scene& scene) {
  std::vector<double> y;
  for (const Eigen::MatrixX3d& x : positions) y.push_back(centreOfMass(x, scene.masses).y());
  return y;
}

// Every integrator with plain iterations, and the blend with Anderson-accelerated ("blend+AA"),
// L-BFGS ("blend+LB") and Newton-CG ("blend+NT") solves, which help where its IM candidate is short
// of converged (docs/method.md).
struct MotionSeries {
  Integrator integrator;
  stabint::Acceleration acceleration;
  std::string label;
};
// The blend with each solver: the default (L-BFGS) first, then plain iterations, Anderson and
// Newton-CG.
std::vector<MotionSeries> blendSolverSeries() {
  const stabint::Acceleration standard = stabint::SimulatorOptions{}.acceleration;
  std::vector<MotionSeries> series{{Integrator::EnergyBlend, standard, "blend"}};
  for (stabint::Acceleration acceleration : {stabint::Acceleration::None, stabint::Acceleration::Anderson,
                                             stabint::Acceleration::LBFGS, stabint::Acceleration::Newton})
    if (acceleration != standard)
      series.push_back(
          {Integrator::EnergyBlend, acceleration, std::string("blend") + accelerationSuffix(acceleration)});
  return series;
}

// Every integrator with the default solver, then the blend with each other solver.
std::vector<MotionSeries> motionSeries() {
  const stabint::Acceleration standard = stabint::SimulatorOptions{}.acceleration;
  std::vector<MotionSeries> series;
  for (Integrator i : stabint::allIntegrators()) series.push_back({i, standard, stabint::integratorName(i)});
  for (const MotionSeries& m : blendSolverSeries())
    if (m.acceleration != standard) series.push_back(m);
  return series;
}

// Every integrator on a scene with a motion reference (cloth, chain, handle cloth, stiff cloth,
// stiff drag).
void referenceScene(const StudyScene& s, const StudyOptions& options, MotionTable& table, SeriesWriter& series,
                    CsvWriter& references) {
  const MotionReference& ref = motionReference(s, options);
  references << s.key << ref.method << ref.check_substeps << ref.positions.size() - 1 << ref.horizon()
             << ref.energy_error << ref.self_rms << ref.self_mean_k << ref.seconds << (ref.from_cache ? 1 : 0)
             << ref.available;
  references.endRow();
  series.addReference(s, ref);
  const double drop_ref = comDropWithinOneSecond(ref.positions, s.scene, ref.frame_step);
  const double period_ref = swingPeriod(comHeights(ref.positions, s.scene), ref.frame_step);
  table.addReference(s, ref, drop_ref, period_ref);
  for (const MotionSeries& m : motionSeries()) {
    RunSpec spec;
    spec.integrator = m.integrator;
    spec.acceleration = m.acceleration;
    spec.frames = framesFor(s, options, kRealTimeSeconds);
    spec.backend = options.backend;
    const JudgedRun j = judgedRun(s, spec, options);
    MotionRow row{s.key, m.label, &j};
    row.com_drop = comDropWithinOneSecond(j.run.positions, s.scene, s.frame_step);
    row.com_drop_ref = drop_ref;
    row.period = swingPeriod(comHeights(j.run.positions, s.scene), s.frame_step);
    row.period_ref = period_ref;
    table.add(row, s.frame_step, spec.iterations, spec.frames);
    series.add(s, row.integrator, j.run);
  }
}

// The handle cloth's blend against how far its solves converge (docs/method.md, "Which solver is
// the default"): mean K over 5-10 s against the reference's and the target's gain over the run
// (H*_end - H*_0: booked work minus damping; the reference's energy gains its own). The work is
// booked right (a converged IM solve from the same states books it to 1 %); what differs is how
// far each solve detunes the driven swing (handleResponse). Writes handle_convergence.csv.
void handleConvergence(const StudyOptions& options) {
  const StudyScene s = handleClothScene();
  const MotionReference& ref = motionReference(s, options);
  CsvWriter csv(joinPath(options.out, "handle_convergence.csv"),
                {"solver", "iterations", "tolerance", "mean_K_ratio", "target_gain_J", "reference_gain_J"});
  const double ref_gain = ref.energy.back() - ref.energy.front();
  std::printf(
      "\nHandle cloth, blend, by the solve's convergence: mean K 5-10 s / reference's, H* gained over\n"
      "the run [J] (the reference's energy gains %.3g J)\n%-8s %10s %10s %8s %10s\n",
      ref_gain, "solver", "iterations", "tolerance", "K/Kref", "H* gain");
  struct Case {
    stabint::Acceleration solver;
    int iterations;
    double tolerance;
  };
  for (const Case& c : {Case{stabint::Acceleration::None, 10, 0.0}, Case{stabint::Acceleration::None, 30, 0.0},
                        Case{stabint::Acceleration::LBFGS, 10, 0.0}, Case{stabint::Acceleration::LBFGS, 30, 0.0},
                        Case{stabint::Acceleration::LBFGS, 0, 1e-10}}) {
    RunSpec spec;
    spec.acceleration = c.solver;
    spec.iterations = c.iterations > 0 ? c.iterations : 10;
    spec.tolerance = c.tolerance;
    spec.max_iterations = 5000;
    spec.frames = framesFor(s, options, kRealTimeSeconds);
    spec.backend = options.backend;
    const JudgedRun j = judgedRun(s, spec, options);
    const double gain = j.run.samples.back().target - j.run.samples.front().target;
    csv << stabint::accelerationName(c.solver) << c.iterations << c.tolerance << j.motion.mean_k_ratio << gain
        << ref_gain;
    csv.endRow();
    std::printf("%-8s %10d %10.0e %8.3g %10.3g\n", stabint::accelerationName(c.solver), c.iterations, c.tolerance,
                j.motion.mean_k_ratio, gain);
  }
  std::fflush(stdout);
}

// The handle cloth is a lightly damped pendulum driven near its resonance (the reference's mean K
// over 5-10 s is 12x larger with the handle at 0.6 Hz than at 0.5 Hz), so its mean K ratio at
// one frequency measures how far a solver detunes the swing, not whether the forcing is booked
// right: a solver whose period is too long puts the resonance onto the 0.5 Hz handle. The blend
// of every solver against the handle's frequency, each against its own small-step reference.
// Writes handle_response.csv (mean K ratio per frequency and solver) and prints, per solver, the
// mean |ln(K/K_ref)| over the frequencies (0: the reference's response curve).
void handleResponse(const StudyOptions& options) {
  const std::vector<MotionSeries> solvers = blendSolverSeries();
  CsvWriter csv(joinPath(options.out, "handle_response.csv"),
                {"frequency_Hz", "series", "mean_K_ratio", "reference_mean_K_J"});
  std::printf("\nHandle cloth, the blend against the handle's frequency: mean K 5-10 s / reference's\n%-6s %12s", "Hz",
              "ref K [mJ]");
  for (const MotionSeries& m : solvers) std::printf(" %10s", m.label.c_str());
  std::printf("\n");
  std::vector<double> log_error(solvers.size(), 0.0);
  for (double f : kHandleFrequencies) {
    const StudyScene s = handleClothScene(f);
    double ref_k = 0.0;
    std::printf("%-6.2f", f);
    std::vector<double> ratios;
    for (std::size_t i = 0; i < solvers.size(); ++i) {
      RunSpec spec;
      spec.integrator = solvers[i].integrator;
      spec.acceleration = solvers[i].acceleration;
      spec.frames = framesFor(s, options, kRealTimeSeconds);
      spec.backend = options.backend;
      const JudgedRun j = judgedRun(s, spec, options);
      ref_k = j.motion.mean_k_ref;
      ratios.push_back(j.motion.mean_k_ratio);
      log_error[i] += std::abs(std::log(j.motion.mean_k_ratio)) / static_cast<double>(kHandleFrequencies.size());
      csv << f << solvers[i].label << j.motion.mean_k_ratio << j.motion.mean_k_ref;
      csv.endRow();
    }
    std::printf(" %12.3f", 1e3 * ref_k);
    for (double r : ratios) std::printf(" %10.3g", r);
    std::printf("\n");
  }
  std::printf("%-19s", "mean |ln ratio|");
  for (double e : log_error) std::printf(" %10.2f", e);
  std::printf("\n");
  std::fflush(stdout);
}

// Angular momentum about the centre of mass kept by each integrator over 10 s of free spin.
void spinningBar(bool general, const StudyOptions& options, MotionTable& table) {
  const StudyScene s = spinningBarScene(general);
  const Eigen::Vector3d l0 = angularMomentum(s.scene.positions, s.scene.velocities, s.scene.masses);
  for (const MotionSeries& m : motionSeries()) {
    const Integrator i = m.integrator;
    RunSpec spec;
    spec.integrator = i;
    spec.acceleration = m.acceleration;
    spec.frames = framesFor(s, options, kSpinSeconds);
    spec.backend = options.backend;
    spec.stop_factor = kExplodeFactor;  // the explicit integrators explode within frames
    // E_avail of a free body is H_0 (its equilibrium potential, at rest in its rest shape, is
    // zero), so the energy verdict needs no equilibrium search.
    spec.energy_unit = stabint::Simulator(s.scene, stabint::SimulatorOptions{}).energy().total();
    Eigen::Vector3d l = l0;
    JudgedRun j;
    j.run = simulate(s.scene, spec, [&](int, const stabint::Simulator& sim) {
      l = angularMomentum(sim.positions(), sim.velocities(), s.scene.masses);
    });
    // No reference here: conservation is the reference.
    j.energy = energyMetrics(j.run, spec.energy_unit);
    j.motion.flicker = kineticFlicker(kineticSeries(j.run), kFlickerFloor * j.energy.available);
    j.motion.verdict = combinedVerdict(j.energy.verdict, kNaN, j.motion.flicker);
    MotionRow row{s.key, m.label, &j};
    row.l_kept = l.dot(l0) / l0.squaredNorm();
    row.l_error = (l - l0).norm() / l0.norm();
    row.energy_kept = j.energy.h_end / j.energy.h0;
    table.add(row, s.frame_step, spec.iterations, spec.frames);
  }
}

// One particle on a sinusoidally moving pin: linear, so implicit midpoint is exact in one
// iteration and its energy obeys H1 - H0 = [U(x1, t1) - U(x1, tm)] + [U(x0, tm) - U(x0, t0)]
// (U(x, t) = k/2 |x - q(t)|^2, tm the step's midpoint time). The forcing rule books H*; a rule
// consistent with IM keeps H* = H_IM to round-off.
void movingPin(const StudyOptions& options) {
  CsvWriter csv(joinPath(options.out, "moving_pin.csv"), {"stiffness", "h", "steps", "max_abs_target_minus_H_IM_J",
                                                          "max_abs_IM_balance_residual_J", "H_IM_max_J"});
  std::printf(
      "\nOne particle (1 kg) on a pin moving as %g m sin(2 pi %g Hz t), h = 1/30, IM, 10 s:\n"
      "%10s %18s %22s %12s\n",
      kMovingPinAmplitude, kMovingPinFrequency, "k [N/m]", "max|H* - H_IM| [J]", "IM balance residual [J]",
      "max H_IM [J]");
  for (double k : {1e2, 1e4, 1e6}) {
    const StudyScene s = movingPinScene(k);
    const stabint::Pin& pin = s.scene.pins.at(0);
    auto u = [&](const Eigen::Vector3d& x, double t) { return 0.5 * k * (x - pin.target.at(t)).squaredNorm(); };
    RunSpec spec;
    spec.integrator = Integrator::ImplicitMidpoint;
    spec.frames = framesFor(s, options, kRealTimeSeconds);
    spec.backend = options.backend;
    double max_target_gap = 0.0, max_residual = 0.0, h_max = 0.0;
    Eigen::Vector3d x_prev = s.scene.positions.row(0).transpose();
    double h_prev = 0.5 * s.scene.masses[0] * s.scene.velocities.row(0).squaredNorm() + u(x_prev, 0.0);
    simulate(s.scene, spec, [&](int frame, const stabint::Simulator& sim) {
      const double t1 = frame * s.frame_step, t0 = t1 - s.frame_step, tm = 0.5 * (t0 + t1);
      const Eigen::Vector3d x1 = sim.positions().row(0).transpose();
      const double h_now = sim.energy().total();
      const double work = (u(x1, t1) - u(x1, tm)) + (u(x_prev, tm) - u(x_prev, t0));
      max_residual = std::max(max_residual, std::abs(h_now - h_prev - work));
      max_target_gap = std::max(max_target_gap, std::abs(sim.target() - h_now));
      h_max = std::max(h_max, h_now);
      x_prev = x1;
      h_prev = h_now;
    });
    csv << k << s.frame_step << spec.frames << max_target_gap << max_residual << h_max;
    csv.endRow();
    std::printf("%10.0e %18.4g %22.3g %12.4g\n", k, max_target_gap, max_residual, h_max);
  }
  std::fflush(stdout);
}

}  // namespace

double comY(const RunResult& run, const Scene& scene, size_t frame) {
  return frame < run.positions.size() ? centreOfMass(run.positions[frame], scene.masses).y() : kNaN;
}

JudgedRun judgedRun(const StudyScene& scene, RunSpec spec, const StudyOptions& options) {
  const MotionReference& ref = motionReference(scene, options);
  spec.frame_step = scene.frame_step;
  spec.record_positions = true;
  JudgedRun j;
  j.run = simulate(scene.scene, spec);
  j.energy = energyMetrics(j.run, ref.available);
  j.motion = motionMetrics(j.run, spec.frames, ref, j.energy);
  return j;
}

void runMotion(const StudyOptions& options) {
  ensureDirectory(options.out);
  CsvWriter references(joinPath(options.out, "motion_reference.csv"),
                       {"scene", "method", "check_substeps", "frames", "horizon_s", "energy_error_rel",
                        "self_rms_0_1s_m", "self_mean_K_ratio", "compute_s", "cached", "E_avail"});
  SeriesWriter series(options);
  {
    MotionTable table(options);
    for (const StudyScene& s :
         {clothScene(), chainScene(), handleClothScene(), clothScene(kStiffClothStretch), stiffDragScene()})
      referenceScene(s, options, table, series, references);
    spinningBar(false, options, table);
    spinningBar(true, options, table);
  }
  std::printf(
      "ref rows: the small-step reference (method in the last column); their max|H-H*| column is the\n"
      "reference's own energy error; motion_reference.csv has its check against half the steps per frame.\n");
  std::printf(
      "ms/fr*: median wall clock per frame; drop1s: largest drop of the centre of mass within 1 s [m];\n"
      "period: swing period of the centre of mass's height (mean spacing of its minima) [s];\n"
      "whole: blend steps that took the partner whole (alpha = 1); L kept: angular momentum after 10 s\n"
      "along the initial one, L.L0/|L0|^2 (spinning bars).\n");
  movingPin(options);
  handleConvergence(options);
  handleResponse(options);
  std::printf("\n");
}

}  // namespace study
