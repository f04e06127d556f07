#pragma once
// The OpenCL batch tests' comparison of a batch on the device with the same batch on the CPU
// reference (tests/test_opencl_batch.cpp, test_opencl_batch_input.cpp).
#include <stabint/batch.hpp>
#include <stabint/simulator.hpp>

#include "test_opencl_support.hpp"

#include <gtest/gtest.h>

#include <cstddef>
#include <string>

namespace stabint::testing {

/// An integrator, time step and number of steps of a batch test.
struct BatchCase {
  Integrator integrator;
  double time_step;
  int steps;
};

// A scene's step report on the device against the CPU batch's: the energy booked in the step
// (forcing, damping, friction, the contact projection), the target and the energies within `tol`.
inline void expectBookedAndEnergiesNear(const StepReport& g, const StepReport& w, double tol) {
  EXPECT_NEAR(g.forcing, w.forcing, tol);
  EXPECT_NEAR(g.damping, w.damping, tol);
  EXPECT_NEAR(g.friction, w.friction, tol);
  EXPECT_NEAR(g.contact_projection, w.contact_projection, tol);
  EXPECT_NEAR(g.target, w.target, tol);
  EXPECT_NEAR(g.energy.kinetic, w.energy.kinetic, tol);
  EXPECT_NEAR(g.energy.elastic, w.energy.elastic, tol);
  EXPECT_NEAR(g.energy.external, w.energy.external, tol);
}

// One step of the OpenCL batch and of the CPU batch: no refusal on the device, every scene's step
// and time the CPU batch's and its report within `tol` of the scene's E_scale
// (expectBookedAndEnergiesNear). Returns the CPU batch's report.
inline const BatchStepReport& stepBothAndExpectNear(BatchSimulator& opencl, BatchSimulator& cpu, double tol, int step) {
  const BatchStepReport got = opencl.step();
  const BatchStepReport& want = cpu.step();
  for (std::size_t s = 0; s < want.scenes.size(); ++s) {
    SCOPED_TRACE("scene " + std::to_string(s) + " step " + std::to_string(step));
    EXPECT_TRUE(got.refusals[s].empty()) << got.refusals[s];
    EXPECT_EQ(got.scenes[s].step, want.scenes[s].step);
    EXPECT_EQ(got.scenes[s].time, want.scenes[s].time);
    expectBookedAndEnergiesNear(got.scenes[s], want.scenes[s], tol * cpu.energyScale(int(s)));
  }
  return want;
}

inline SimulatorOptions batchOptions(const BatchCase& c, BackendKind backend, Precision precision) {
  SimulatorOptions o;
  o.integrator = c.integrator;
  o.time_step = c.time_step;
  o.iterations = 5;
  o.backend = backend;
  o.opencl = openclOptions(precision);
  return o;
}

}  // namespace stabint::testing
