// The small-step motion reference of a scene (issue 8, "Motion in the study"): the scene run with
// a step far below the real-time one, sampled at the scene's frame times, long enough for the
// motion metrics (10 s for the mean kinetic energy over 5-10 s, 1 s for trajectory errors).
//
// Symplectic Euler with h/2000 is what the reviewer used: explicit, so every step is one
// force pass with nothing left unconverged, symplectic, so its energy error stays bounded (below
// 3e-4 E_avail on the cloth) instead of drifting, and 30 us per step on the 20 x 20 cloth
// (10 s in about 17 s). Scenes whose explicit step would be expensive use converged implicit
// midpoint instead (StudyScene::reference_*): the tet bar's per-tet rotations make an SE step
// cost 270 us, and its 1e7 N/m pins need h/200 for stability alone.
//
// Sharpness is checked, not assumed: the same run with half the steps per frame (the check run)
// gives the RMS difference over 0-1 s and the ratio of mean K over the K window, and the
// reference's own energy error max |H - H*| is reported (H* books forcing and damping).
#include "cache.hpp"
#include "study.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace study {

namespace {

constexpr int kMaxIterations = 2000;  // implicit references: converged solves
// --quick (smoke tests): at most 1 s and about 60,000 reference steps (2 s of work on the cloth).
constexpr double kQuickSeconds = 1.0;
constexpr int kQuickSteps = 60000;

int horizonFrames(const StudyScene& scene, const StudyOptions& options) {
  const int frames = static_cast<int>(std::lround(scene.reference_seconds / scene.frame_step));
  if (!options.quick) return frames;
  const int quick = static_cast<int>(std::lround(kQuickSeconds / scene.frame_step));
  return std::max(2, std::min({frames, quick, kQuickSteps / scene.reference_substeps}));
}

// The library's damping is a factor per step: with s steps per frame the reference applies
// 1 - (1 - d)^(1/s) per step, the same decay per frame of the non-rigid velocity as the
// real-time runs get from d.
Scene withDampingPer(const Scene& scene, int substeps) {
  Scene s = scene;
  for (stabint::Body& b : s.bodies) b.damping = 1.0 - std::pow(1.0 - b.damping, 1.0 / substeps);
  return s;
}

RunResult referenceRun(const StudyScene& scene, int substeps, int frames) {
  RunSpec spec;
  spec.integrator = scene.reference_integrator;
  spec.frame_step = scene.frame_step;
  spec.substeps = substeps;
  spec.tolerance = scene.reference_tolerance;
  // Plain iterations to the tolerance, as the cached references were computed (the key does not
  // name the solver).
  spec.acceleration = stabint::Acceleration::None;
  spec.max_iterations = kMaxIterations;
  spec.frames = frames;
  spec.backend = BackendKind::CpuReference;  // the oracle backend, whatever --backend says
  spec.record_positions = true;
  RunResult run = simulate(withDampingPer(scene.scene, substeps), spec);
  if (run.blew_up_frame >= 0 || run.frames_done != frames)
    throw std::runtime_error("motion reference for " + scene.key + " (" + std::to_string(substeps) +
                             " steps per frame) blew up: " + run.blow_up_message);
  return run;
}

std::string methodName(const StudyScene& scene, int substeps) {
  std::ostringstream m;
  m << stabint::integratorName(scene.reference_integrator) << " h/" << substeps;
  if (scene.reference_tolerance > 0.0) m << " tol " << scene.reference_tolerance;
  return m.str();
}

std::vector<double> toPayload(const MotionReference& r) {
  std::vector<double> p = {static_cast<double>(r.positions.size()),
                           static_cast<double>(r.positions.front().rows()),
                           static_cast<double>(r.substeps),
                           static_cast<double>(r.check_substeps),
                           r.available,
                           r.energy_error,
                           r.self_rms,
                           r.self_mean_k,
                           r.seconds};
  appendFrames(p, r.positions);
  p.insert(p.end(), r.kinetic.begin(), r.kinetic.end());
  p.insert(p.end(), r.energy.begin(), r.energy.end());
  return p;
}

bool fromPayload(const std::vector<double>& payload, int frames, MotionReference& r) {
  PayloadReader in(payload);
  double count = 0, particles = 0, substeps = 0, check = 0;
  if (!in.next(count) || count != frames + 1 || !in.next(particles) || !in.next(substeps) || !in.next(check) ||
      !in.next(r.available) || !in.next(r.energy_error) || !in.next(r.self_rms) || !in.next(r.self_mean_k) ||
      !in.next(r.seconds))
    return false;
  r.substeps = static_cast<int>(substeps);
  r.check_substeps = static_cast<int>(check);
  if (!readFrames(in, frames + 1, static_cast<int>(particles), r.positions)) return false;
  r.kinetic.assign(frames + 1, 0.0);
  r.energy.assign(frames + 1, 0.0);
  return in.next(r.kinetic.data(), r.kinetic.size()) && in.next(r.energy.data(), r.energy.size()) && in.done();
}

MotionReference compute(const StudyScene& scene, int frames) {
  MotionReference r;
  r.substeps = scene.reference_substeps;
  r.check_substeps = scene.reference_substeps / 2;
  const RunResult fine = referenceRun(scene, r.substeps, frames);
  const RunResult check = referenceRun(scene, r.check_substeps, frames);
  r.positions = fine.positions;
  r.kinetic = kineticSeries(fine);
  for (const FrameSample& f : fine.samples) r.energy.push_back(f.total());
  r.available = availableEnergy(scene);
  if (scene.driven_energy_unit) {
    const double equilibrium = fine.samples.front().total() - r.available;
    for (const FrameSample& f : fine.samples) r.available = std::max(r.available, f.total() - equilibrium);
  }
  for (const FrameSample& f : fine.samples)
    r.energy_error = std::max(r.energy_error, std::abs(f.total() - f.target) / r.available);
  const int one_second = std::min(frames, static_cast<int>(std::lround(kLongRmsSeconds / scene.frame_step)));
  r.self_rms = rmsTrajectoryError(check.positions, fine.positions, one_second);
  const TimeWindow w = kineticWindow(scene.frame_step * frames);
  r.self_mean_k = meanOverWindow(kineticSeries(check), scene.frame_step, w.from, w.to) /
                  meanOverWindow(r.kinetic, scene.frame_step, w.from, w.to);
  r.seconds = fine.seconds + check.seconds;
  for (const auto& x : r.positions)
    if (!x.allFinite()) throw std::runtime_error("motion reference for " + scene.key + " is not finite");
  return r;
}

}  // namespace

const MotionReference& motionReference(const StudyScene& scene, const StudyOptions& options) {
  const int frames = horizonFrames(scene, options);
  std::ostringstream d;
  d.precision(17);
  d << cacheDescription(scene) << " | motion reference " << methodName(scene, scene.reference_substeps) << " check h/"
    << scene.reference_substeps / 2 << " frame_step=" << scene.frame_step << " frames=" << frames
    << " damping per step rescaled, maxit=" << kMaxIterations << " format=1";
  const std::string description = d.str();
  static LoadedReferences<MotionReference> loaded;
  return loaded.get(description, [&] {
    const std::string path = cachePath(joinPath(options.out, "cache"), scene.key + "-motion", description);
    MotionReference ref;
    std::vector<double> payload;
    if (readCache(path, description, payload) && fromPayload(payload, frames, ref)) {
      ref.from_cache = true;
      progress("motion reference " + scene.key + ": cached " + path);
    } else {
      progress("motion reference " + scene.key + ": computing (" + methodName(scene, scene.reference_substeps) +
               " and h/" + std::to_string(scene.reference_substeps / 2) + ", " + std::to_string(frames) + " frames)");
      ref = compute(scene, frames);
      writeCache(path, description, toPayload(ref));
      std::ostringstream done;
      done.precision(3);
      done << "motion reference " << scene.key << ": " << ref.seconds << " s, energy error " << ref.energy_error
           << " E_avail, check run differs by " << ref.self_rms << " m RMS over 0-1 s, mean K ratio " << ref.self_mean_k
           << "; wrote " << path;
      progress(done.str());
    }
    ref.method = methodName(scene, ref.substeps);
    ref.frame_step = scene.frame_step;
    return ref;
  });
}

}  // namespace study
