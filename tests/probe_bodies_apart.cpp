// A probe, not a test (docs/results/method_measurements.md, "Rigid motions in the initial
// Hessian"): a swinging cloth pinned at one edge (the default cloth grid turned horizontal) beside
// a free tet bar thrown up and spinning 2 m away, 30 steps at the default 10 iterations, with BE
// and the blend. Per integrator it prints each body's RMS distance from the run converged to
// 1e-10, and the cloth's alone in a scene of its own.
// Usage: build/tests/probe_bodies_apart [steps]
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "contact_scenes.hpp"
#include "stabint/simulator.hpp"

namespace {

using namespace stabint;

Scene swingingCloth() {
  Scene c = makeClothGrid(ClothGridParams{});
  const double top = c.positions.col(1).maxCoeff();
  for (int i = 0; i < c.numParticles(); ++i) {  // turned to the horizontal about its pinned top edge
    c.positions(i, 2) = c.positions(i, 1) - top;
    c.positions(i, 1) = top;
  }
  c.rest_positions = c.positions;
  return c;
}

Scene besideASpinningBar(const Scene& cloth) {
  Scene bar = makeTetBar(TetBarParams{});
  bar.pins.clear();
  bar.positions.col(0).array() += 2.0;
  bar.rest_positions = bar.positions;
  Scene s = testing::combined(cloth, bar);
  s.pins = cloth.pins;
  const int n = cloth.numParticles();
  const Eigen::Vector3d centre = s.positions.bottomRows(bar.numParticles()).colwise().mean().transpose();
  for (int i = n; i < s.numParticles(); ++i) {
    const Eigen::Vector3d r = s.positions.row(i).transpose() - centre;
    s.velocities.row(i) = (Eigen::Vector3d(0.0, 3.0, 0.0) + Eigen::Vector3d(0.5, 1.0, 4.0).cross(r)).transpose();
  }
  return s;
}

Eigen::MatrixX3d run(const Scene& s, Integrator integrator, bool converged, int steps) {
  SimulatorOptions o;
  o.integrator = integrator;
  if (converged) {
    o.tolerance = 1e-10;
    o.max_iterations = 3000;
  }
  Simulator sim(s, o);
  for (int k = 0; k < steps; ++k) sim.step();
  return sim.positions();
}

double rms(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b, int first, int count) {
  return std::sqrt((a.middleRows(first, count) - b.middleRows(first, count)).rowwise().squaredNorm().mean());
}

}  // namespace

int main(int argc, char** argv) {
  const int steps = argc > 1 ? std::atoi(argv[1]) : 30;
  const Scene cloth = swingingCloth();
  const Scene both = besideASpinningBar(cloth);
  const int n = cloth.numParticles(), m = both.numParticles() - n;
  std::printf("integrator, the cloth beside the bar [m], the bar [m], the cloth alone [m]\n");
  for (const Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend}) {
    const Eigen::MatrixX3d alone = run(cloth, integrator, false, steps),
                           alone_ref = run(cloth, integrator, true, steps);
    const Eigen::MatrixX3d x = run(both, integrator, false, steps), ref = run(both, integrator, true, steps);
    std::printf("%s, %.3g, %.3g, %.3g\n", integratorName(integrator), rms(x, ref, 0, n), rms(x, ref, n, m),
                rms(alone, alone_ref, 0, n));
  }
  return 0;
}
