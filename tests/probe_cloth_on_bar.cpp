// A probe, not a test (docs/results/method_measurements.md, "Self-contact books"), of a cloth
// dropped on a body, 60 steps each with the blend:
// - the 30 x 30 cloth of `testing::clothOnBar` thrown down at 2, 4, 8 and 12 m/s onto tet bars of
//   1e4, 1e5, 1e6 and 1e7 Pa, the cloth of 1, 10 and 30 times its mass (48 drops, 4 mm), as
//   SelfContactRun.AClothOnSoftStiffAndHeavyVariantsKeepsTheBand drops 12 of them;
// - the upper cloth of `testing::clothOnCloth` thrown at 0, 2, 4, 8 and 12 m/s onto the lower one,
//   of 1, 10 and 30 times its mass (15 drops, 3 mm, the default supports).
// Per drop it prints the blend's largest max(H - H*) over its band tau = energy_tolerance (K + E_int
// + E_scale) and the step it was reached at; per set, how many drops stayed within 1.5 bands.
// Usage: build/tests/probe_cloth_on_bar [steps]
#include <cstdio>
#include <cstdlib>
#include <utility>

#include "contact_scenes.hpp"
#include "stabint/simulator.hpp"
#include "energy_band.hpp"

namespace {

// The largest (H - H*) / tau of `scene` over `steps` steps, and the step it was reached at.
std::pair<double, int> worstBands(const stabint::Scene& scene, double thickness, int steps) {
  stabint::SimulatorOptions o;
  o.self_contact_thickness = thickness;
  stabint::Simulator sim(scene, o);
  double bands = 0.0;
  int at = -1;
  for (int k = 0; k < steps; ++k) {
    const stabint::StepReport& report = sim.step();
    const double tau = stabint::testing::energyBand(sim, report);
    const double over = (report.energy.total() - report.target) / tau;
    if (over > bands) bands = over, at = k;
  }
  return {bands, at};
}

}  // namespace

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
        const auto [bands, at] = worstBands(scene, 4e-3, steps);
        std::printf("%g, %g, %g, %.3g, %d\n", stiffness, speed, mass, bands, at);
        ++drops;
        within += bands <= 1.5 ? 1 : 0;
      }
    }
  }
  std::printf("%d of %d drops onto a bar within 1.5 bands\n", within, drops);
  within = drops = 0;
  std::printf("speed [m/s], upper cloth mass [x], max(H - H*) / tau, at step\n");
  for (const double speed : {0.0, 2.0, 4.0, 8.0, 12.0}) {
    for (const double mass : {1.0, 10.0, 30.0}) {
      Scene scene = testing::clothOnCloth();
      const int upper = scene.numParticles() / 2;
      scene.velocities.bottomRows(upper).col(1).setConstant(-speed);
      scene.masses.tail(upper) *= mass;
      const auto [bands, at] = worstBands(scene, 3e-3, steps);
      std::printf("%g, %g, %.3g, %d\n", speed, mass, bands, at);
      ++drops;
      within += bands <= 1.5 ? 1 : 0;
    }
  }
  std::printf("%d of %d drops onto a cloth within 1.5 bands\n", within, drops);
  return 0;
}
