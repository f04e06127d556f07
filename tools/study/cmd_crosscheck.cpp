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
                {"scene", "integrator", "frames", "max_position_diff_m", "max_energy_diff_rel", "opencl_device",
                 "status"});
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
        csv << s.key << stabint::integratorName(i) << frames << "nan" << "nan" << "none" << "skipped";
        csv.endRow();
        std::printf("  crosscheck skipped: %s\n", e.what());
        return;
      }
      double dx = 0.0, de = 0.0;
      const size_t n = std::min(cpu.positions.size(), ocl.positions.size());
      for (size_t f = 0; f < n; ++f) {
        dx = std::max(dx, (cpu.positions[f] - ocl.positions[f]).cwiseAbs().maxCoeff());
        de = std::max(de, std::abs(cpu.samples[f].total() - ocl.samples[f].total()) / available);
      }
      const bool same_length = cpu.positions.size() == ocl.positions.size();
      std::string label = device;
      for (char& c : label)
        if (c == ',') c = ';';
      csv << s.key << stabint::integratorName(i) << frames << dx << de << label
          << (same_length ? "compared" : "different-blow-up");
      csv.endRow();
      std::printf("  crosscheck %-6s %-5s max |x_cpu - x_ocl| = %.3g m, max |H_cpu - H_ocl| = %.3g E_avail%s\n",
                  s.key.c_str(), stabint::integratorName(i), dx, de, same_length ? "" : " (blew up differently)");
    }
  }
  std::fflush(stdout);
}

}  // namespace study
