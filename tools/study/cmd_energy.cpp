// `energy`: energy over time for the paper's scenes with BE, BDF2, IM and the blend: the hanging
// tet bar released under gravity (height of its free end, H, H*) and the pinned cloth; plus the
// cloth's positions at one frame for BE and the blend (a rendered still).
#include "csv.hpp"
#include "study.hpp"

#include <cstdio>

namespace study {

namespace {

const std::vector<Integrator> kIntegrators = {Integrator::BackwardEuler, Integrator::BDF2, Integrator::ImplicitMidpoint,
                                              Integrator::EnergyBlend};
constexpr int kStillFrame = 60;  // 2 s: the cloth has swung down once and folds are visible

double freeEndHeight(const StudyScene& s, const Eigen::MatrixX3d& x) {
  double sum = 0.0;
  for (int k = 0; k < s.free_end_count; ++k) sum += x(s.free_end_first + k * s.free_end_stride, 1);
  return sum / s.free_end_count;
}

void writeStill(const StudyOptions& options, const StudyScene& s, Integrator integrator, int frame,
                const Eigen::MatrixX3d& x) {
  CsvWriter csv(joinPath(options.out, std::string("cloth_still_") + stabint::integratorName(integrator) + ".csv"),
                {"i", "j", "x", "y", "z", "nx", "ny", "frame"});
  for (int j = 0; j < s.grid_ny; ++j) {
    for (int i = 0; i < s.grid_nx; ++i) {
      const int r = j * s.grid_nx + i;
      csv << i << j << x(r, 0) << x(r, 1) << x(r, 2) << s.grid_nx << s.grid_ny << frame;
      csv.endRow();
    }
  }
}

}  // namespace

void runEnergy(const StudyOptions& options) {
  ensureDirectory(options.out);
  const int frames = options.quick ? 60 : 300;
  for (const StudyScene& s : {tetBarScene(), clothScene()}) {
    const bool bar = s.key == "tetbar";
    CsvWriter csv(joinPath(options.out, "energy_" + s.key + ".csv"),
                  {"integrator", "backend", "frame", "time", "H", "H_target", "kinetic", "elastic", "external",
                   "E_avail", "free_end_y", "com_y", "branch", "alpha", "iterations"});
    for (Integrator i : kIntegrators) {
      RunSpec spec;
      spec.integrator = i;
      spec.frames = frames;
      spec.backend = options.backend;
      const JudgedRun j = judgedRun(s, spec, options);
      const RunResult& run = j.run;
      if (!bar && run.positions.size() > static_cast<size_t>(kStillFrame))
        writeStill(options, s, i, kStillFrame, run.positions[kStillFrame]);
      for (size_t f = 0; f < run.samples.size(); ++f) {
        const FrameSample& fs = run.samples[f];
        csv << stabint::integratorName(i) << stabint::backendName(options.backend) << f << fs.time << fs.total()
            << fs.target << fs.kinetic << fs.elastic << fs.external << j.energy.available
            << (bar ? freeEndHeight(s, run.positions[f]) : 0.0) << comY(run, s.scene, f)
            << stabint::blendBranchName(fs.branch) << fs.alpha << fs.iterations;
        csv.endRow();
      }
      const Metrics& m = j.energy;
      std::printf(
          "  energy %-6s %-5s drift %+8.3f E_avail, max |H - H*| %.3g E_avail, mean K %.3g x reference's, "
          "flicker %.3g: %s%s\n",
          s.key.c_str(), stabint::integratorName(i), m.drift, m.max_target_dev, j.motion.mean_k_ratio, j.motion.flicker,
          j.motion.verdict.c_str(),
          run.blew_up_frame >= 0 ? (", blew up at frame " + std::to_string(run.blew_up_frame)).c_str() : "");
      std::fflush(stdout);
    }
    progress("energy " + s.key + " done");
  }
}

}  // namespace study
