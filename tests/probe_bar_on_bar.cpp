// A probe, not a test (README, self-contact): testing::barOnBar's upper bar thrown down at 0, 4 and
// 12 m/s onto the lower one, both bars of 1e4, 1e5 and 1e6 Pa, self-contact 4 mm, 60 steps of the
// blend. Per drop it prints the largest (H - H*) over the band tau, the steps with an inverted
// element (a tet whose signed volume is <= 0), whether one is inverted at the end, and the most
// surface triangle pairs that intersect at any step (CGAL's exact test).
// Usage: build/tests/probe_bar_on_bar
#include <algorithm>
#include <cstdio>

#include "contact_scenes.hpp"
#include "stabint/simulator.hpp"
#include "triangle_intersections.hpp"
#include "energy_band.hpp"

namespace {

using namespace stabint;

// The smallest signed volume (times 6) of the scene's tets at x.
double smallestVolume(const Scene& scene, const Eigen::MatrixX3d& x) {
  double smallest = 1e300;
  for (const Tet& tet : scene.tets) {
    const auto& v = tet.vertices;
    const Eigen::Vector3d a = x.row(v[0]).transpose(), b = x.row(v[1]).transpose(), c = x.row(v[2]).transpose(),
                          d = x.row(v[3]).transpose();
    smallest = std::min(smallest, (b - a).cross(c - a).dot(d - a));
  }
  return smallest;
}

}  // namespace

int main() {
  std::printf(
      "stiffness [Pa], speed [m/s], max(H - H*) / tau, steps inverted, inverted at the end, most crossing pairs\n");
  for (const double stiffness : {1e4, 1e5, 1e6}) {
    for (const double speed : {0.0, 4.0, 12.0}) {
      Scene scene = testing::barOnBar();
      for (Tet& tet : scene.tets) tet.stiffness = stiffness;
      scene.velocities.bottomRows(scene.numParticles() / 2).col(1).setConstant(-speed);
      const std::vector<std::array<int, 3>> surface = tetSurface(scene.tets);
      SimulatorOptions o;
      o.self_contact_thickness = 4e-3;
      Simulator sim(scene, o);
      double bands = 0.0;
      int inverted = 0;
      int crossing = 0;
      bool inverted_at_end = false;
      for (int k = 0; k < 60; ++k) {
        const StepReport& r = sim.step();
        const double tau = testing::energyBand(sim, r);
        bands = std::max(bands, (r.energy.total() - r.target) / tau);
        inverted_at_end = smallestVolume(scene, sim.positions()) <= 0.0;
        inverted += inverted_at_end ? 1 : 0;
        crossing = std::max(crossing, testing::intersectingTrianglePairs(sim.positions(), surface));
      }
      std::printf("%g, %g, %.3g, %d, %s, %d\n", stiffness, speed, bands, inverted, inverted_at_end ? "yes" : "no",
                  crossing);
    }
  }
  return 0;
}
