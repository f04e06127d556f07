// `teaser`: the paper's teaser picture. A 40 x 40 cloth of triangle strain and bending hinges,
// pinned at the two corners of its top edge and released 30 degrees below the horizontal (the
// main job's cloth, twice as fine and without springs), stepped with BE, BDF2 and the blend from
// the same start (h = 1/30, 10 iterations). Writes the surface (teaser_triangles.csv), the
// positions of every frame per integrator (teaser_<integrator>.bin: float32 little-endian,
// frames x particles x 3, frame 0 the start) and every frame's energies (teaser_energy.csv);
// bench/teaser.py draws the animation, the still and the energy curves from them.
#include "csv.hpp"
#include "study.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace study {

namespace {

constexpr int kTeaserSide = 40;
constexpr double kTeaserSeconds = 6.0;
constexpr double kGather = 0.75;      // the pinned corners start this fraction of the width apart
constexpr double kRipple = 0.03;      // m: amplitude of the start's folds
constexpr double kRippleWaves = 3.0;  // across the width

// The main job's tilted cloth, gathered: its width starts compressed to kGather about the middle
// (free: the membrane may compress to strain_min = kGather - 0.05, as cloth buckles rather than
// resists) and rippled across its plane, the ripple growing from zero at the pinned edge. So the
// folds have a deterministic start, and what each integrator keeps of them is what the picture
// shows.
StudyScene teaserScene(int side) {
  StudyScene s = triangleClothScene(side, 1e3, kGather - 0.05);
  Scene& sc = s.scene;
  const double tilt = 30.0 * M_PI / 180.0;
  const Eigen::Vector3d normal(0.0, std::cos(tilt), std::sin(tilt));  // of the tilted plane
  const double width = sc.rest_positions.col(0).maxCoeff(), middle = 0.5 * width;
  for (int r = 0; r < sc.numParticles(); ++r) {
    const double u = sc.positions(r, 0) / width;
    const double along = std::hypot(sc.positions(r, 1), sc.positions(r, 2));  // from the pinned edge
    sc.positions(r, 0) = middle + kGather * (sc.positions(r, 0) - middle);
    sc.positions.row(r) += (kRipple * along * std::sin(2.0 * M_PI * kRippleWaves * u)) * normal.transpose();
  }
  for (stabint::Pin& pin : sc.pins) pin.target.position = sc.positions.row(pin.vertex).transpose();
  s.equilibrium_start.col(0) = middle + kGather * (s.equilibrium_start.col(0).array() - middle);
  s.key = "teaser";
  return s;
}

void writePositions(const std::string& path, const std::vector<Eigen::MatrixX3d>& frames) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error("cannot write " + path);
  std::vector<float> row;
  for (const Eigen::MatrixX3d& x : frames) {
    row.clear();
    for (Eigen::Index r = 0; r < x.rows(); ++r)
      for (int c = 0; c < 3; ++c) row.push_back(static_cast<float>(x(r, c)));
    out.write(reinterpret_cast<const char*>(row.data()), static_cast<std::streamsize>(row.size() * sizeof(float)));
  }
  if (!out) throw std::runtime_error("write failed: " + path);
}

double lastSecondKinetic(const RunResult& run, double frame_step) {
  const size_t count = std::min(run.samples.size(), static_cast<size_t>(1.0 / frame_step + 0.5));
  double sum = 0.0;
  for (size_t f = run.samples.size() - count; f < run.samples.size(); ++f) sum += run.samples[f].kinetic;
  return count > 0 ? sum / count : 0.0;
}

}  // namespace

void runTeaser(const StudyOptions& options) {
  ensureDirectory(options.out);
  const StudyScene s = teaserScene(options.quick ? 12 : kTeaserSide);
  const Scene& scene = s.scene;
  {
    CsvWriter tri(joinPath(options.out, "teaser_triangles.csv"), {"a", "b", "c"});
    for (const auto& t : scene.triangles) {
      tri << t[0] << t[1] << t[2];
      tri.endRow();
    }
  }
  // Energies in joules: the study's E_avail needs the static equilibrium, whose search takes
  // minutes on this free-to-compress cloth, and the picture needs no more than H - H_0.
  CsvWriter csv(joinPath(options.out, "teaser_energy.csv"),
                {"integrator", "backend", "particles", "frame", "time", "H", "H_target", "kinetic", "elastic",
                 "external", "ms_per_frame"});
  for (Integrator i : {Integrator::BackwardEuler, Integrator::BDF2, Integrator::EnergyBlend}) {
    RunSpec spec;
    spec.integrator = i;
    spec.frames = static_cast<int>(kTeaserSeconds / spec.frame_step + 0.5);
    if (options.quick) spec.frames = 30;
    spec.backend = options.backend;
    spec.record_positions = true;
    const RunResult run = simulate(scene, spec);
    writePositions(joinPath(options.out, std::string("teaser_") + stabint::integratorName(i) + ".bin"), run.positions);
    for (size_t f = 0; f < run.samples.size(); ++f) {
      const FrameSample& fs = run.samples[f];
      csv << stabint::integratorName(i) << stabint::backendName(options.backend) << scene.numParticles() << f << fs.time
          << fs.total() << fs.target << fs.kinetic << fs.elastic << fs.external << run.ms_per_frame();
      csv.endRow();
    }
    const FrameSample& start = run.samples.front();
    const FrameSample& end = run.samples.back();
    std::printf(
        "  teaser %-5s %d frames, %.3g ms/frame, H %.4g J -> %.4g J (H* %.4g J), mean K over the last second %.3g "
        "J%s\n",
        stabint::integratorName(i), run.frames_done, run.ms_per_frame(), start.total(), end.total(), end.target,
        lastSecondKinetic(run, spec.frame_step), run.blew_up_frame >= 0 ? ", blew up" : "");
    std::fflush(stdout);
  }
  progress("teaser: " + std::to_string(scene.numParticles()) + " particles, " + stabint::elementSummary(scene));
}

}  // namespace study
