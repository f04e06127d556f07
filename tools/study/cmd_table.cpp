// `table`: the per-integrator energy behaviour on the stiff chain pendulum and the cloth
// (h = 1/30, 10 iterations, 300 frames), printed and written to energy_table.csv.
#include "csv.hpp"
#include "study.hpp"

#include <cstdio>

namespace study {

void runTable(const StudyOptions& options) {
  ensureDirectory(options.out);
  const int frames = options.quick ? 60 : 300;
  CsvWriter csv(joinPath(options.out, "energy_table.csv"),
                {"scene",      "integrator",   "backend",       "frames",         "frames_done", "E_scale_sim",
                 "E_avail",    "H0",           "H_end",         "H_min",          "H_max",       "max_dev_target_rel",
                 "drift_rel",  "damping_rel",  "blew_up_frame", "ms_per_frame",   "branches",    "partner_whole_steps",
                 "rms_0_1s_m", "mean_K_ratio", "flicker",       "energy_verdict", "verdict"});
  std::printf(
      "\nEnergy behaviour, h = 1/30 s, 10 iterations, %d frames, backend %s.\n"
      "Relative columns are in units of E_avail = H0 - (potential of the static equilibrium):\n"
      "the energy the scene can turn into motion. E_scale is Simulator::energyScale().\n",
      frames, stabint::backendName(options.backend));
  std::printf("%-6s %-10s %9s %9s %10s %10s %10s %10s %9s %9s %8s %7s %8s %18s  %s\n", "scene", "integ", "E_scale",
              "E_avail", "H0", "H_end", "H_min", "H_max", "max|H-H*|", "drift", "blow-up", "ms/fr", "damping",
              "branches", "verdict (energy, motion)");
  for (const StudyScene& s : {chainScene(), clothScene()}) {
    // The six integrators, then the blend with a BE partner budget equal to the main one (label
    // "blend-be10"), to show what the default partner budget of 3 iterations gives up.
    std::vector<std::pair<Integrator, int>> rows;
    for (Integrator i : stabint::allIntegrators()) rows.push_back({i, RunSpec{}.be_iterations});
    rows.push_back({Integrator::EnergyBlend, 10});
    for (const auto& [i, be_iterations] : rows) {
      const std::string label = std::string(stabint::integratorName(i)) +
                                (be_iterations != RunSpec{}.be_iterations ? "-be" + std::to_string(be_iterations) : "");
      RunSpec spec;
      spec.integrator = i;
      spec.be_iterations = be_iterations;
      spec.frames = frames;
      spec.backend = options.backend;
      const JudgedRun j = judgedRun(s, spec, options);
      const RunResult& run = j.run;
      const Metrics& m = j.energy;
      csv << s.key << label << stabint::backendName(options.backend) << frames << run.frames_done << run.energy_scale
          << m.available << m.h0 << m.h_end << m.h_min << m.h_max << m.max_target_dev << m.drift << m.damping
          << run.blew_up_frame << run.ms_per_frame() << run.branchSummary() << run.partner_whole << j.motion.rms_long
          << j.motion.mean_k_ratio << j.motion.flicker << m.verdict << j.motion.verdict;
      csv.endRow();
      char blow[16] = "-";
      if (run.blew_up_frame >= 0) std::snprintf(blow, sizeof blow, "%d", run.blew_up_frame);
      std::printf("%-6s %-10s %9.3g %9.3g %10.4g %10.4g %10.4g %10.4g %9.3g %+9.3g %8s %7.3f %+8.3g %18s  %s, %s\n",
                  s.key.c_str(), label.c_str(), run.energy_scale, m.available, m.h0, m.h_end, m.h_min, m.h_max,
                  m.max_target_dev, m.drift, blow, run.ms_per_frame(), m.damping, run.branchSummary().c_str(),
                  m.verdict.c_str(), j.motion.verdict.c_str());
      std::fflush(stdout);
    }
  }
  std::printf(
      "verdict: exploded = blew up or max |H - H0| > %g E_avail; over-damped = lost > %g %% of E_avail "
      "(mean H of the last 10 %% of frames); else stable.\nMotion (against the small-step reference, see "
      "`motion`): frozen = mean K over 5-10 s < %g x the reference's; jittery = flicker of K > %g.\n\n",
      kExplodeFactor, 100.0 * kOverDampedFraction, kFrozenFraction, kJitteryFlicker);
}

}  // namespace study
