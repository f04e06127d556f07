// A probe, not a test (docs/results/method_measurements.md, "Before the solve: the approach
// stopped"): the 62.5 kg tet bar of `testing::barOnCloth` dropped onto a 30 x 30 cloth lying on the
// ground, as the scene places it and 10 cm higher turned about (0.3, 0.5, 0.8) by +-0.1, +-0.2 and
// +-0.3 rad, at 0, 4, 8 and 12 m/s (28 drops, 90 steps each, the blend, 4 mm). Per drop it prints
// the blend's max(H - H*) over the run's largest kinetic energy and over its band
// tau = energy_tolerance (K + E_int + E_scale), as SelfContactRun's drop tests measure them, and
// the highest the cloth (lying 5 mm above the ground) rises.
// Usage: build/tests/probe_bar_on_cloth [steps]
#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "contact_scenes.hpp"
#include "stabint/simulator.hpp"
#include "energy_band.hpp"

int main(int argc, char** argv) {
  using namespace stabint;
  const int steps = argc > 1 ? std::atoi(argv[1]) : 90;
  const int cloth = 900;
  std::printf("turn [rad], speed [m/s], max(H - H*) / K_max, max(H - H*) / tau, the cloth's highest point [m]\n");
  for (const double turn : {0.0, -0.3, -0.2, -0.1, 0.1, 0.2, 0.3}) {
    for (const double speed : {0.0, 4.0, 8.0, 12.0}) {
      Scene scene = testing::barOnCloth(speed);
      if (turn != 0.0) {
        const int bar = scene.numParticles() - cloth;
        const Eigen::Vector3d centre = scene.positions.topRows(bar).colwise().mean().transpose();
        const Eigen::Matrix3d r =
            Eigen::AngleAxisd(turn, Eigen::Vector3d(0.3, 0.5, 0.8).normalized()).toRotationMatrix();
        for (int i = 0; i < bar; ++i)
          scene.positions.row(i) =
              (centre + Eigen::Vector3d(0.0, 0.1, 0.0) + r * (scene.positions.row(i).transpose() - centre)).transpose();
        scene.rest_positions = scene.positions;
      }
      SimulatorOptions o;
      o.self_contact_thickness = 4e-3;
      Simulator sim(scene, o);
      double excess = 0.0, kinetic = 0.0, bands = 0.0, highest = 0.0;
      for (int k = 0; k < steps; ++k) {
        const StepReport& report = sim.step();
        const double over = report.energy.total() - report.target;
        const double tau = testing::energyBand(sim, report);
        excess = std::max(excess, over);
        kinetic = std::max(kinetic, report.energy.kinetic);
        bands = std::max(bands, over / tau);
        highest = std::max(highest, sim.positions().col(1).tail(cloth).maxCoeff());
      }
      std::printf("%+.1f, %g, %.4g, %.3g, %.3g\n", turn, speed, excess / kinetic, bands, highest);
    }
  }
  return 0;
}
