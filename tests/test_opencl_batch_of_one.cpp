// A batch of one on an OpenCL device steps as that scene's OpenCL Simulator, bit for bit (see
// tests/test_batch_of_one.cpp for the CPU reference): the one-segment reductions take the
// single-scene path.
#include <stabint/batch.hpp>
#include <stabint/simulator.hpp>

#include "batch_scenes.hpp"
#include "test_opencl_support.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace stabint {
namespace {

TEST(OpenCLBatchOfOne, StepsAsItsSimulatorBitForBit) {
  for (Precision precision : {Precision::Double, Precision::Float}) {
    STABINT_SKIP_WITHOUT_OPENCL(precision);
    for (Integrator integrator :
         {Integrator::BackwardEuler, Integrator::BDF2, Integrator::ImplicitMidpoint, Integrator::EnergyBlend}) {
      SimulatorOptions o;
      o.integrator = integrator;
      o.backend = BackendKind::OpenCL;
      o.opencl = testing::openclOptions(precision);
      std::vector<Scene> scenes = testing::mixedBatchScenes();
      for (const Scene& s : testing::contactBatchScenes()) scenes.push_back(s);
      for (std::size_t k = 0; k < scenes.size(); ++k) {
        Simulator alone(scenes[k], o);
        BatchSimulator batch({scenes[k]}, o);
        for (int n = 0; n < 20; ++n) {
          const std::string where = std::string(precisionName(precision)) + " " + integratorName(integrator) +
                                    ", scene " + std::to_string(k) + ", step " + std::to_string(n);
          const StepReport own = alone.step();
          const BatchStepReport& b = batch.step();
          ASSERT_EQ(b.refusals[0], "") << where;
          const StepReport& got = b.scenes[0];
          ASSERT_EQ(got.energy.kinetic, own.energy.kinetic) << where;
          ASSERT_EQ(got.energy.elastic, own.energy.elastic) << where;
          ASSERT_EQ(got.target, own.target) << where;
          ASSERT_EQ(got.branch, own.branch) << where;
          ASSERT_TRUE(batch.positions(0) == alone.positions()) << where;
          ASSERT_TRUE(batch.velocities(0) == alone.velocities()) << where;
        }
      }
    }
  }
}

}  // namespace
}  // namespace stabint
