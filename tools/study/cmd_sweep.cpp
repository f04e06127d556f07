// `reference`: reference trajectories and the accuracy of every integrator at the real-time
// setting (h = 1/30, 10 iterations). `sweep`: speed versus accuracy, iteration budgets for the
// implicit integrators and substeps for the explicit ones.
#include "csv.hpp"
#include "study.hpp"

#include <cstdio>
#include <sstream>

namespace study {

namespace {

struct AccuracyScene {
  StudyScene scene;
  const Reference* reference = nullptr;     // the IM h/16 reference: position error over 2 s
  const MotionReference* motion = nullptr;  // the small-step reference: trajectory error over 0-1 s
  double available = 0.0;
};

std::vector<AccuracyScene> accuracyScenes(const StudyOptions& options) {
  std::vector<AccuracyScene> scenes;
  for (StudyScene s : {clothScene(), triangleClothScene(), tetBarScene()}) {
    AccuracyScene a;
    a.reference = &loadOrComputeReference(s, options);
    a.motion = &motionReference(s, options);
    a.available = a.motion->available;
    a.scene = std::move(s);
    scenes.push_back(std::move(a));
  }
  return scenes;
}

struct Evaluation {
  RunResult run;
  Metrics metrics;
  double position_error = 0.0;
  MotionMetrics motion;  // trajectory errors over 0-0.5 s and 0-1 s against the motion reference
};

Evaluation evaluate(const AccuracyScene& a, RunSpec spec) {
  spec.frames = kReferenceFrames;
  spec.record_positions = true;
  Evaluation e;
  e.run = simulate(a.scene.scene, spec);
  e.metrics = energyMetrics(e.run, a.available);
  e.position_error = positionRmsError(e.run, a.reference->positions);
  e.motion = motionMetrics(e.run, spec.frames, *a.motion, e.metrics);
  return e;
}

bool isExplicit(Integrator i) { return i == Integrator::ForwardEuler || i == Integrator::SymplecticEuler; }

}  // namespace

void runReference(const StudyOptions& options) {
  ensureDirectory(options.out);
  const std::vector<AccuracyScene> scenes = accuracyScenes(options);
  CsvWriter refs(
      joinPath(options.out, "reference.csv"),
      {"scene", "frames", "substeps", "self_error_m", "max_energy_dev_rel", "available_energy", "finite", "cached"});
  for (const AccuracyScene& a : scenes) {
    refs << a.scene.key << kReferenceFrames << a.reference->substeps << a.reference->self_error
         << a.reference->max_energy_dev << a.available << 1 << (a.reference->from_cache ? 1 : 0);
    refs.endRow();
    std::printf(
        "  reference %-6s: IM h/%d converged, finite, max |H - H0| = %.3g %% of E_avail, "
        "self-error (vs h/%d) %.3g m\n",
        a.scene.key.c_str(), a.reference->substeps, 100.0 * a.reference->max_energy_dev, a.reference->substeps / 2,
        a.reference->self_error);
  }

  CsvWriter acc(joinPath(options.out, "accuracy.csv"),
                {"scene", "integrator", "backend", "iterations", "frames", "ms_per_frame", "position_error_m",
                 "rms_0_0.5s_m", "rms_0_1s_m", "drift_rel", "damping_rel", "max_rise_rel", "verdict", "blew_up_frame"});
  for (const AccuracyScene& a : scenes) {
    for (Integrator i : stabint::allIntegrators()) {
      RunSpec spec;
      spec.integrator = i;
      spec.backend = options.backend;
      const Evaluation e = evaluate(a, spec);
      acc << a.scene.key << stabint::integratorName(i) << stabint::backendName(options.backend) << spec.iterations
          << kReferenceFrames << e.run.ms_per_frame() << e.position_error << e.motion.rms_short << e.motion.rms_long
          << e.metrics.drift << e.metrics.damping << e.metrics.max_rise << e.metrics.verdict << e.run.blew_up_frame;
      acc.endRow();
      std::printf(
          "  %-6s %-5s err %9.3g m  (0-1 s vs small-step reference %9.3g m)  drift %+9.3g  damping %+9.3g  %s\n",
          a.scene.key.c_str(), stabint::integratorName(i), e.position_error, e.motion.rms_long, e.metrics.drift,
          e.metrics.damping, e.metrics.verdict.c_str());
    }
  }
  std::fflush(stdout);
}

void runSweep(const StudyOptions& options) {
  ensureDirectory(options.out);
  const std::vector<AccuracyScene> scenes = accuracyScenes(options);
  // 10 is the main job's real-time budget: the motion table compares the other integrators with
  // the blend at its time per frame there (bench/study_charts.py interpolates their curves).
  const std::vector<int> budgets =
      options.quick ? std::vector<int>{1, 4, 10} : std::vector<int>{1, 2, 4, 8, 10, 16, 32};
  // Explicit substeps k = 1, 2, 4, ... up to the first stable k (or 2048): the charts ask where the
  // explicit integrator first runs stable and at what cost, and each further k costs twice the one
  // before for a point further right (the next one: about 100 s of the main job). The cloth's
  // corner pins (1e5 N/m on ~5e-5 kg) need omega h < 2, i.e. k ~ 1000.
  const int max_substeps = options.quick ? 64 : 2048;
  CsvWriter csv(joinPath(options.out, "sweep.csv"),
                {"scene", "integrator", "backend", "iterations", "substeps", "frames", "ms_per_frame",
                 "ms_per_frame_median", "position_error_m", "rms_0_0.5s_m", "rms_0_1s_m", "drift_rel", "damping_rel",
                 "max_rise_rel", "verdict", "blew_up_frame"});
  // Every integrator with the default solver (L-BFGS), then the blend and BE with plain iterations
  // ("<integrator>+PD"), Anderson acceleration ("+AA") and Newton-CG ("+NT"): the shift each
  // gives on the chart.
  struct Series {
    Integrator integrator;
    stabint::Acceleration acceleration;
  };
  const stabint::Acceleration standard = stabint::SimulatorOptions{}.acceleration;
  std::vector<Series> series;
  for (Integrator i : stabint::allIntegrators()) series.push_back({i, standard});
  for (stabint::Acceleration acceleration : {stabint::Acceleration::None, stabint::Acceleration::Anderson,
                                             stabint::Acceleration::LBFGS, stabint::Acceleration::Newton})
    if (acceleration != standard)
      for (Integrator i : {Integrator::BackwardEuler, Integrator::EnergyBlend}) series.push_back({i, acceleration});
  for (const AccuracyScene& a : scenes) {
    for (const Series& sr : series) {
      const Integrator i = sr.integrator;
      const std::string label = std::string(stabint::integratorName(i)) + accelerationSuffix(sr.acceleration);
      const bool explicit_integrator = isExplicit(i);
      std::vector<int> values = budgets;
      if (explicit_integrator) {
        values.clear();
        for (int k = 1; k <= max_substeps; k *= 2) values.push_back(k);
      }
      for (int value : values) {
        RunSpec spec;
        spec.integrator = i;
        spec.acceleration = sr.acceleration;
        spec.backend = options.backend;
        if (explicit_integrator)
          spec.substeps = value;
        else
          spec.iterations = value;
        spec.stop_factor = kExplodeFactor;  // an exploded run's numbers stop meaning anything
        spec.energy_unit = a.available;
        const Evaluation e = evaluate(a, spec);
        csv << a.scene.key << label << stabint::backendName(options.backend) << (explicit_integrator ? 0 : value)
            << spec.substeps << kReferenceFrames << e.run.ms_per_frame() << e.run.medianMsPerFrame() << e.position_error
            << e.motion.rms_short << e.motion.rms_long << e.metrics.drift << e.metrics.damping << e.metrics.max_rise
            << e.metrics.verdict << e.run.blew_up_frame;
        csv.endRow();
        if (explicit_integrator && e.metrics.verdict != "exploded") break;
      }
      progress("sweep " + a.scene.key + " " + label + " done");
    }
  }
}

}  // namespace study
