// `crosscheck`: the OpenCL backend against the CPU reference on the study's scenes, so the
// accuracy experiments (run on the CPU backend by default) stand for both backends.
#include "csv.hpp"
#include "study.hpp"

#include <cmath>
#include <cstdio>

namespace study {

void runCrosscheck(const StudyOptions& options) {
  ensureDirectory(options.out);
  const int frames = options.quick ? 10 : 30;
  CsvWriter csv(joinPath(options.out, "backend_check.csv"),
                {"scene", "integrator", "frames", "compared_frames", "max_position_diff_m", "max_energy_diff_rel",
                 "max_relative_position_diff", "opencl_device", "status"});
  std::string device;
  for (const StudyScene& s : {chainScene(), clothScene(), tetBarScene()}) {
    const double available = availableEnergy(s);
    for (Integrator i : stabint::allIntegrators()) {
      RunSpec spec;
      spec.integrator = i;
      spec.frames = frames;
      spec.record_positions = true;
      const RunResult cpu = simulate(s.scene, spec);
      spec.backend = BackendKind::OpenCL;
      RunResult ocl;
      try {
        ocl = simulate(s.scene, spec, [&](int frame, const stabint::Simulator& sim) {
          if (frame == 1) device = sim.backendDescription();
        });
      } catch (const stabint::OpenCLError& e) {
        csv << s.key << stabint::integratorName(i) << frames << 0 << "nan"
            << "nan"
            << "nan"
            << "none"
            << "skipped";
        csv.endRow();
        std::printf("  crosscheck skipped: %s\n", e.what());
        return;
      }
      // Compare while the CPU run is not exploded: after that, both runs amplify round-off
      // exponentially and their difference says nothing about the backends.
      double dx = 0.0, de = 0.0;
      const size_t n = std::min(cpu.positions.size(), ocl.positions.size());
      const double h0 = cpu.samples.front().total();
      size_t compared = 0;
      for (size_t f = 0; f < n; ++f) {
        if (!(std::abs(cpu.samples[f].total() - h0) <= kExplodeFactor * available)) break;
        dx = std::max(dx, (cpu.positions[f] - ocl.positions[f]).cwiseAbs().maxCoeff());
        de = std::max(de, std::abs(cpu.samples[f].total() - ocl.samples[f].total()) / available);
        ++compared;
      }
      // Over all common frames, relative to the size of the state: meaningful for exploding
      // explicit runs too (they grow exponentially, and so does the round-off).
      double rel = 0.0;
      for (size_t f = 0; f < n; ++f) {
        const double scale = std::max(cpu.positions[f].cwiseAbs().maxCoeff(), 1e-300);
        rel = std::max(rel, (cpu.positions[f] - ocl.positions[f]).cwiseAbs().maxCoeff() / scale);
      }
      const bool same_length = cpu.positions.size() == ocl.positions.size();
      std::string label = device;
      for (char& c : label)
        if (c == ',') c = ';';
      csv << s.key << stabint::integratorName(i) << frames << static_cast<int>(compared) - 1 << dx << de << rel << label
          << (same_length ? "compared" : "different-blow-up");
      csv.endRow();
      std::printf(
          "  crosscheck %-6s %-5s %2d frames: max |x_cpu - x_ocl| = %.3g m, max |H_cpu - H_ocl| = %.3g E_avail; "
          "relative, all frames %.2g%s\n",
          s.key.c_str(), stabint::integratorName(i), static_cast<int>(compared) - 1, dx, de, rel,
          same_length ? "" : " (blew up at a different frame)");
    }
  }
  std::fflush(stdout);
}

}  // namespace study
