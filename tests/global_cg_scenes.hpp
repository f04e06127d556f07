#pragma once
// What the CG global step's tests share (tests/test_global_cg.cpp on the CPU reference,
// tests/test_opencl_global_cg.cpp across backends): two small scenes, a spring cloth (a 2-D
// Laplacian) and a tet bar (3-D), so both matrix structures the Jacobi preconditioner meets are
// covered; converged CG options; and a run that changes L by a grab and an element change.
#include <stabint/builders.hpp>
#include <stabint/simulator.hpp>

namespace stabint::testing {

inline Scene cgClothScene() {
  ClothGridParams p;
  p.nx = 12;
  p.ny = 10;
  return makeClothGrid(p);
}

inline Scene cgTetScene() {
  TetBarParams p;
  p.nx = 6;
  p.ny = 2;
  p.nz = 2;
  p.stiffness = 2e4;
  return makeTetBar(p);
}

/// Backward Euler with CG global steps solved to a relative residual of 1e-12 (the cap is never
/// reached on these scenes), so a run tracks the factor's to round-off times cond(K_c).
inline SimulatorOptions convergedCgOptions() {
  SimulatorOptions o;
  o.integrator = Integrator::BackwardEuler;
  o.global_solve = GlobalSolve::ConjugateGradient;
  o.cg_iterations = 10000;
  o.cg_tolerance = 1e-12;
  return o;
}

/// 15 steps of the cloth scenes with a grab of vertex 40 dragged by (0.1, 0.2, 0), four springs
/// made softer and the release: every kind of change of L.
inline void stepWithChangesOfL(Simulator& sim) {
  for (int n = 0; n < 5; ++n) sim.step();
  const int pin = sim.grab(40, 1e4);
  sim.setPinTarget(pin, sim.pinTarget(pin) + Eigen::Vector3d(0.1, 0.2, 0.0));
  for (int n = 0; n < 5; ++n) sim.step();
  sim.setElementStiffness(ElementKind::Spring, {0, 1, 2, 3}, 10.0);
  sim.release(pin);
  for (int n = 0; n < 5; ++n) sim.step();
}

}  // namespace stabint::testing
