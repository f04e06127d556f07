// A probe, not a test (docs/results/method_measurements.md, "Lifting off the ground"): a 40 x 40
// spring cloth (1 m) lying on the ground (friction 0.5) is lifted by a hand (`Simulator::grab`,
// 1e4 N/m) at the middle of an edge, up at 1 m/s and across at 0.4 m/s, for 30 steps, with BE,
// BDF2 and the blend at 10 and 100 iterations, the ground's `elastic_ratio` 1 (the default) and 0,
// pairs leaving within the solve (`contact_release` 1) at the default ratio, and the same lift
// without ground and gravity. Per run it prints the hand's work booked in H* (H*_end - H_0), the
// held particle's largest distance behind the hand and the largest elastic energy: what the solve
// leaves unconverged while the pairs of the contact set keep their weights in the global matrix
// as the cloth leaves the ground.
// Usage: build/tests/probe_lift_off
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "contact_scenes.hpp"
#include "stabint/simulator.hpp"

namespace {

using namespace stabint;

void lift(Integrator integrator, int iterations, bool ground, double elastic_ratio, int release = 0) {
  Scene s = testing::horizontalCloth(40, 0.005);
  if (ground) {
    s.colliders = {testing::groundPlane(0.0, Collider{}.stiffness, 0.5)};
    s.colliders[0].elastic_ratio = elastic_ratio;
  } else {
    s.gravity.setZero();
  }
  const int held = testing::edgeMiddle(s);
  SimulatorOptions o;
  o.backend = BackendKind::CpuReference;
  o.integrator = integrator;
  o.iterations = iterations;
  o.contact_release = release;
  Simulator sim(s, o);
  const double h0 = sim.energy().total();
  const Eigen::Vector3d start = sim.positions().row(held).transpose();
  const int hand = sim.grab(held, 1e4);
  double lag = 0.0, elastic = 0.0, target = h0;
  for (int f = 1; f <= 30; ++f) {
    const double t = f * o.time_step;
    const Eigen::Vector3d at = start + Eigen::Vector3d(0.0, std::min(0.8, t), 0.4 * t);
    sim.setPinTarget(hand, at);
    const StepReport& r = sim.step();
    lag = std::max(lag, (at - sim.positions().row(held).transpose()).norm());
    elastic = std::max(elastic, r.energy.elastic);
    target = r.target;
  }
  std::printf("%-5s, %3d, %-6s, %4.1f, %d, %8.3f, %7.4f, %7.3f\n", integratorName(integrator), iterations,
              ground ? "ground" : "none", ground ? elastic_ratio : 0.0, release, target - h0, lag, elastic);
}

}  // namespace

int main() {
  std::printf(
      "integrator, iterations, ground, elastic_ratio, contact_release, hand's work [J], largest lag [m], largest "
      "E_int [J]\n");
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::BDF2, Integrator::EnergyBlend}) {
    for (int iterations : {10, 100}) {
      for (double ratio : {1.0, 0.0}) lift(integrator, iterations, true, ratio);
      lift(integrator, iterations, true, 1.0, 1);
      lift(integrator, iterations, false, 0.0);
    }
  }
  return 0;
}
