// The reference trajectory of a scene: implicit midpoint with a step of h/16 and local/global
// iterations converged to a 1e-10 relative change of the objective, sampled at frame times.
// With converged solves and omega h small for the motion that matters, IM is second-order
// accurate and does not gain energy the way the 10-iteration real-time IM does. The same run
// with h/8 gives a self-convergence estimate of the reference's own error. Cached on disk.
#include "cache.hpp"
#include "study.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace study {

namespace {

constexpr double kFrameStep = 1.0 / 30.0;
constexpr double kTolerance = 1e-10;
constexpr int kMaxIterations = 2000;

RunSpec referenceSpec(int substeps) {
  RunSpec spec;
  spec.integrator = Integrator::ImplicitMidpoint;
  spec.frame_step = kFrameStep;
  spec.substeps = substeps;
  spec.tolerance = kTolerance;
  // Plain iterations to the tolerance, as the cached references were computed (the key does not
  // name the solver; any converged solver gives the same trajectory to the tolerance).
  spec.acceleration = stabint::Acceleration::None;
  spec.max_iterations = kMaxIterations;
  spec.frames = kReferenceFrames;
  spec.backend = BackendKind::CpuReference;  // the oracle backend, whatever --backend says
  spec.record_positions = true;
  return spec;
}

bool fromPayload(const std::vector<double>& payload, Reference& ref) {
  PayloadReader in(payload);
  double frames = 0, particles = 0, substeps = 0;
  if (!in.next(frames) || !in.next(particles) || !in.next(substeps) || !in.next(ref.self_error) ||
      !in.next(ref.max_energy_dev) || frames != kReferenceFrames)
    return false;
  ref.substeps = static_cast<int>(substeps);
  if (!readFrames(in, kReferenceFrames + 1, static_cast<int>(particles), ref.positions)) return false;
  ref.energy.assign(kReferenceFrames + 1, 0.0);
  return in.next(ref.energy.data(), ref.energy.size()) && in.done();
}

std::vector<double> toPayload(const Reference& ref) {
  std::vector<double> payload = {static_cast<double>(ref.positions.size() - 1),
                                 static_cast<double>(ref.positions.front().rows()), static_cast<double>(ref.substeps),
                                 ref.self_error, ref.max_energy_dev};
  appendFrames(payload, ref.positions);
  payload.insert(payload.end(), ref.energy.begin(), ref.energy.end());
  return payload;
}

// The reference from <out>/cache/, or computed and written there.
Reference loadOrCompute(const StudyScene& scene, const std::string& description, const StudyOptions& options) {
  const std::string path = cachePath(joinPath(options.out, "cache"), scene.key, description);
  Reference ref;
  std::vector<double> payload;
  if (readCache(path, description, payload) && fromPayload(payload, ref)) {
    ref.from_cache = true;
    progress("reference " + scene.key + ": cached " + path);
    return ref;
  }
  ref = Reference{};
  progress("reference " + scene.key + ": computing (IM, h/" + std::to_string(kReferenceSubsteps) +
           ", converged iterations, " + std::to_string(kReferenceFrames) + " frames)");
  const RunResult fine = simulate(scene.scene, referenceSpec(kReferenceSubsteps));
  if (fine.blew_up_frame >= 0 || fine.frames_done != kReferenceFrames)
    throw std::runtime_error("reference for " + scene.key + " blew up: " + fine.blow_up_message);
  const RunResult coarse = simulate(scene.scene, referenceSpec(kReferenceSubsteps / 2));
  ref.substeps = kReferenceSubsteps;
  ref.positions = fine.positions;
  for (const FrameSample& f : fine.samples) ref.energy.push_back(f.total());
  ref.self_error = positionRmsError(coarse, ref.positions);
  const double available = availableEnergy(scene);
  for (double e : ref.energy)
    ref.max_energy_dev = std::max(ref.max_energy_dev, std::abs(e - ref.energy.front()) / available);
  for (const auto& x : ref.positions)
    if (!x.allFinite()) throw std::runtime_error("reference for " + scene.key + " is not finite");
  writeCache(path, description, toPayload(ref));
  std::ostringstream done;
  done << "reference " << scene.key << ": " << fine.seconds + coarse.seconds << " s, wrote " << path;
  progress(done.str());
  return ref;
}

}  // namespace

const Reference& loadOrComputeReference(const StudyScene& scene, const StudyOptions& options) {
  std::ostringstream d;
  d << cacheDescription(scene) << " | reference IM h=1/30/" << kReferenceSubsteps << " tol=" << kTolerance
    << " maxit=" << kMaxIterations << " frames=" << kReferenceFrames << " self-check h/" << kReferenceSubsteps / 2
    << " format=2";
  const std::string description = d.str();
  // Kept once loaded (LoadedReferences): a reference `prefetch` computed counts as computed by
  // this run in reference.csv's `cached`.
  static LoadedReferences<Reference> loaded;
  return loaded.get(description, [&] { return loadOrCompute(scene, description, options); });
}

}  // namespace study
