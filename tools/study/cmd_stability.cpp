// `stability`: stiffness x step size grid per integrator on the chain pendulum and the tet bar;
// each cell classified stable / over-damped / exploded over a fixed number of steps.
#include "csv.hpp"
#include "study.hpp"

#include <cmath>
#include <cstdio>
#include <map>
#include <utility>

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
  // Every cell's scene, built once: the grids' scenes in order, stiffness by stiffness.
  struct Cell {
    std::string key;
    double stiffness;
    Scene scene;
    double available;
  };
  std::vector<Cell> cells;
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
      cells.push_back({g.key, k, std::move(s.scene), available});
    }
  }
  std::vector<Scene> scenes;
  std::vector<double> available;
  for (const Cell& c : cells) {
    scenes.push_back(c.scene);
    available.push_back(c.available);
  }
  // One batch per step size and integrator steps every cell at once (docs/method.md, "Batches"):
  // each cell's run is its own Simulator's to round-off, and a cell that explodes is refused alone.
  std::map<std::pair<int, Integrator>, std::vector<RunResult>> runs;
  for (int rate : rates) {
    for (Integrator i : stabint::allIntegrators()) {
      RunSpec spec;
      spec.integrator = i;
      spec.frame_step = 1.0 / rate;
      spec.frames = steps;
      spec.backend = options.backend;
      spec.stop_factor = kExplodeFactor;
      runs[{rate, i}] = simulateBatch(scenes, spec, available);
    }
    progress("stability h=1/" + std::to_string(rate) + " done");
  }
  for (std::size_t c = 0; c < cells.size(); ++c) {
    for (int rate : rates) {
      for (Integrator i : stabint::allIntegrators()) {
        const RunResult& run = runs[{rate, i}][c];
        const Metrics m = energyMetrics(run, cells[c].available);
        csv << cells[c].key << stabint::integratorName(i) << stabint::backendName(options.backend) << cells[c].stiffness
            << 1.0 / rate << steps << run.frames_done << cells[c].available << m.max_rise << m.damping << m.drift
            << run.blew_up_frame << m.verdict;
        csv.endRow();
      }
    }
  }
}

}  // namespace study
