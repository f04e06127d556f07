// `stability`: stiffness x step size grid per integrator on the chain pendulum and the tet bar;
// each cell classified stable / over-damped / exploded over a fixed number of steps.
#include "csv.hpp"
#include "study.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace study {

void runStability(const StudyOptions& options) {
  ensureDirectory(options.out);
  const int steps = options.quick ? 40 : 150;
  const std::vector<int> rates = {120, 60, 30, 15};  // h = 1/rate
  struct Grid {
    std::string key;
    std::vector<double> stiffness;
  };
  // Each range is centred on the scene's default stiffness (chain 1e4 N/m, tet bar 1e5 Pa,
  // triangle cloth 1e3 N/m of triangle strain).
  const std::vector<Grid> grids = {{"chain", {1e2, 1e3, 1e4, 1e5, 1e6}},
                                   {"cloth_triangles", {1e1, 1e2, 1e3, 1e4, 1e5}},
                                   {"tetbar", {1e3, 1e4, 1e5, 1e6, 1e7}}};
  CsvWriter csv(joinPath(options.out, "stability.csv"),
                {"scene", "integrator", "backend", "stiffness", "h", "steps", "steps_done", "E_avail", "max_rise_rel",
                 "damping_rel", "drift_rel", "blew_up_step", "verdict"});
  for (const Grid& g : grids) {
    for (double k : g.stiffness) {
      const bool bar = g.key == "tetbar";
      StudyScene s = g.key == "chain" ? chainScene(k) : bar ? tetBarScene(k) : triangleClothScene(20, k);
      // Pins scale with the element stiffness: with the builders' fixed stiff pins (1e6 N/m on a
      // 0.01 kg chain particle) the pins alone decide the explicit integrators' fate in every
      // cell. Chain: the pin is as stiff as a link; triangle cloth: as stiff as the membrane
      // (N/m). Tet bar: k times the cell size (N/m from Pa), about the stiffness of one cell.
      const double cell = s.scene.rest_positions.col(0).maxCoeff() / 8.0;
      for (stabint::Pin& pin : s.scene.pins) pin.stiffness = bar ? k * cell : k;
      const double available = availableEnergy(s);
      for (int rate : rates) {
        for (Integrator i : stabint::allIntegrators()) {
          RunSpec spec;
          spec.integrator = i;
          spec.frame_step = 1.0 / rate;
          spec.frames = steps;
          spec.backend = options.backend;
          spec.stop_factor = kExplodeFactor;
          spec.energy_unit = available;
          const RunResult run = simulate(s.scene, spec);
          const Metrics m = energyMetrics(run, available);
          csv << g.key << stabint::integratorName(i) << stabint::backendName(options.backend) << k << spec.frame_step
              << steps << run.frames_done << available << m.max_rise << m.damping << m.drift << run.blew_up_frame
              << m.verdict;
          csv.endRow();
        }
      }
      std::ostringstream line;
      line << "stability " << g.key << " k=" << k << " done";
      progress(line.str());
    }
  }
}

}  // namespace study
