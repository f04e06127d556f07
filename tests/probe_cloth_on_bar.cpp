// A probe, not a test (docs/results/method_measurements.md, "Self-contact books"): the 30 x 30
// cloth of `testing::clothOnBar` thrown down at 2, 4, 8 and 12 m/s onto tet bars of 1e4, 1e5, 1e6
// and 1e7 Pa, the cloth of 1, 10 and 30 times its mass (48 drops, 60 steps each, the blend, 4 mm),
// as SelfContactRun.AClothOnSoftStiffAndHeavyVariantsKeepsTheBand drops 12 of them. Per drop it
// prints the blend's largest max(H - H*) over its band tau = energy_tolerance (K + E_int + E_scale)
// and the step it was reached at; last, how many drops stayed within 1.5 bands.
// Usage: build/tests/probe_cloth_on_bar [steps]
#include <cstdio>
#include <cstdlib>

#include "contact_scenes.hpp"
#include "stabint/simulator.hpp"

int main(int argc, char** argv) {
  using namespace stabint;
  const int steps = argc > 1 ? std::atoi(argv[1]) : 60;
  const int cloth = 900;
  int within = 0, drops = 0;
  std::printf("bar stiffness [Pa], speed [m/s], cloth mass [x], max(H - H*) / tau, at step\n");
  for (const double stiffness : {1e4, 1e5, 1e6, 1e7}) {
    for (const double speed : {2.0, 4.0, 8.0, 12.0}) {
      for (const double mass : {1.0, 10.0, 30.0}) {
        TetBarParams bar;
        bar.stiffness = stiffness;
        Scene scene = testing::clothOnBar(bar);
        scene.velocities.bottomRows(cloth).col(1).setConstant(-speed);
        scene.masses.tail(cloth) *= mass;
        SimulatorOptions o;
        o.self_contact_thickness = 4e-3;
        Simulator sim(scene, o);
        double bands = 0.0;
        int at = -1;
        for (int k = 0; k < steps; ++k) {
          const StepReport& report = sim.step();
          const double tau = o.energy_tolerance * (report.energy.kinetic + report.energy.elastic + sim.energyScale());
          const double over = (report.energy.total() - report.target) / tau;
          if (over > bands) bands = over, at = k;
        }
        std::printf("%g, %g, %g, %.3g, %d\n", stiffness, speed, mass, bands, at);
        ++drops;
        within += bands <= 1.5 ? 1 : 0;
      }
    }
  }
  std::printf("%d of %d drops within 1.5 bands\n", within, drops);
  return 0;
}
