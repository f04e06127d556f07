// The reference trajectory of a scene: implicit midpoint with a step of h/16 and local/global
// iterations converged to a 1e-10 relative change of the objective, sampled at frame times.
// With converged solves and omega h small for the motion that matters, IM is second-order
// accurate and does not gain energy the way the 10-iteration real-time IM does. The same run
// with h/8 gives a self-convergence estimate of the reference's own error. Cached on disk.
#include "study.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace study {

namespace {

constexpr double kFrameStep = 1.0 / 30.0;
constexpr double kTolerance = 1e-10;
constexpr int kMaxIterations = 2000;
constexpr char kMagic[8] = {'S', 'T', 'U', 'D', 'R', 'E', 'F', '1'};

std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

RunSpec referenceSpec(int substeps) {
  RunSpec spec;
  spec.integrator = Integrator::ImplicitMidpoint;
  spec.frame_step = kFrameStep;
  spec.substeps = substeps;
  spec.tolerance = kTolerance;
  spec.max_iterations = kMaxIterations;
  spec.frames = kReferenceFrames;
  spec.backend = BackendKind::CpuReference;  // the oracle backend, whatever --backend says
  spec.record_positions = true;
  return spec;
}

template <typename T>
void put(std::ostream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}
template <typename T>
bool get(std::istream& in, T& value) {
  return static_cast<bool>(in.read(reinterpret_cast<char*>(&value), sizeof(T)));
}

bool readCache(const std::string& path, const std::string& description, Reference& ref) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  char magic[8];
  if (!in.read(magic, 8) || !std::equal(magic, magic + 8, kMagic)) return false;
  std::uint64_t length = 0;
  if (!get(in, length) || length > (1u << 20)) return false;
  std::string stored(length, '\0');
  if (!in.read(&stored[0], static_cast<std::streamsize>(length)) || stored != description) return false;
  std::int32_t frames = 0, particles = 0, substeps = 0;
  if (!get(in, frames) || !get(in, particles) || !get(in, substeps) || !get(in, ref.self_error) ||
      !get(in, ref.max_energy_dev))
    return false;
  if (frames != kReferenceFrames || particles <= 0) return false;
  ref.substeps = substeps;
  ref.positions.assign(frames + 1, Eigen::MatrixX3d(particles, 3));
  ref.energy.assign(frames + 1, 0.0);
  for (auto& x : ref.positions)
    if (!in.read(reinterpret_cast<char*>(x.data()), static_cast<std::streamsize>(sizeof(double) * x.size())))
      return false;
  for (double& e : ref.energy)
    if (!get(in, e)) return false;
  ref.from_cache = true;
  return true;
}

void writeCache(const std::string& path, const std::string& description, const Reference& ref) {
  const std::string temporary = path + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + temporary);
    out.write(kMagic, 8);
    put(out, static_cast<std::uint64_t>(description.size()));
    out.write(description.data(), static_cast<std::streamsize>(description.size()));
    put(out, static_cast<std::int32_t>(ref.positions.size() - 1));
    put(out, static_cast<std::int32_t>(ref.positions.front().rows()));
    put(out, static_cast<std::int32_t>(ref.substeps));
    put(out, ref.self_error);
    put(out, ref.max_energy_dev);
    for (const auto& x : ref.positions)
      out.write(reinterpret_cast<const char*>(x.data()), static_cast<std::streamsize>(sizeof(double) * x.size()));
    for (double e : ref.energy) put(out, e);
    if (!out) throw std::runtime_error("write failed: " + temporary);
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot rename to " + path);
}

}  // namespace

Reference loadOrComputeReference(const StudyScene& scene, const StudyOptions& options) {
  std::ostringstream d;
  d << scene.params << " | reference IM h=1/30/" << kReferenceSubsteps << " tol=" << kTolerance
    << " maxit=" << kMaxIterations << " frames=" << kReferenceFrames << " self-check h/"
    << kReferenceSubsteps / 2 << " format=1";
  const std::string description = d.str();
  std::ostringstream name;
  name << scene.key << '-' << std::hex << std::setw(16) << std::setfill('0') << fnv1a(description) << ".bin";
  const std::string dir = joinPath(options.out, "cache");
  ensureDirectory(dir);
  const std::string path = joinPath(dir, name.str());

  Reference ref;
  if (readCache(path, description, ref)) {
    progress("reference " + scene.key + ": cached " + path);
    return ref;
  }
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
  for (double e : ref.energy) ref.max_energy_dev = std::max(ref.max_energy_dev, std::abs(e - ref.energy.front()) / available);
  for (const auto& x : ref.positions)
    if (!x.allFinite()) throw std::runtime_error("reference for " + scene.key + " is not finite");
  writeCache(path, description, ref);
  std::ostringstream done;
  done << "reference " << scene.key << ": " << fine.seconds + coarse.seconds << " s, wrote " << path;
  progress(done.str());
  return ref;
}

}  // namespace study
