#pragma once
// A cloth driven through every kind of per-frame input (a user-driven pin, user forces) on top of
// a scripted moving pin, shared by the CPU and OpenCL interaction tests.
#include <stabint/stabint.hpp>

#include <cmath>
#include <vector>

namespace stabint::testing {

struct DrivenCloth {
  Scene scene;
  SimulatorOptions options;

  /// The input of the next step: pin 1 follows a sine, particle 5 gets a changing force.
  void drive(Simulator& sim) const {
    const double t1 = sim.time() + options.time_step;
    sim.setPinTarget(1, scene.pins[1].target.position + Eigen::Vector3d(0.1 * std::sin(3 * t1), 0, 0));
    Eigen::MatrixX3d f = Eigen::MatrixX3d::Zero(scene.numParticles(), 3);
    f(5, 2) = 0.05 * std::cos(4 * t1);
    sim.setExternalForces(f);
  }
  /// Positions and velocities after each of `steps` driven steps.
  std::vector<Eigen::MatrixX3d> run(Simulator& sim, int steps) const {
    std::vector<Eigen::MatrixX3d> xs;
    for (int i = 0; i < steps; ++i) {
      drive(sim);
      sim.step();
      xs.push_back(sim.positions());
      xs.push_back(sim.velocities());
    }
    return xs;
  }
};

/// A 7 by 7 spring cloth whose pin 0 moves on a scripted law.
inline DrivenCloth drivenCloth(Integrator integrator) {
  ClothGridParams p;
  p.nx = p.ny = 7;
  DrivenCloth d;
  d.scene = makeClothGrid(p);
  d.scene.pins[0].target.amplitude = Eigen::Vector3d(0.05, 0.0, 0.02);
  d.scene.pins[0].target.frequency = 1.0;
  d.options.integrator = integrator;
  return d;
}

}  // namespace stabint::testing
