// Bad options are rejected with an error naming the field, before anything is allocated, and the
// caller's scene is never modified by a Simulator.
#include <stabint/stabint.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

namespace stabint {
namespace {

void expectRejected(const std::function<void(SimulatorOptions&)>& change, const std::string& field) {
  SimulatorOptions o;
  change(o);
  try {
    Simulator sim(makeLinearOscillator(), o);
    FAIL() << "options with bad " << field << " accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

TEST(SimulatorInput, BadOptionsNameTheField) {
  expectRejected([](SimulatorOptions& o) { o.time_step = 0.0; }, "time_step");
  expectRejected([](SimulatorOptions& o) { o.time_step = -0.01; }, "time_step");
  expectRejected([](SimulatorOptions& o) { o.time_step = std::numeric_limits<double>::quiet_NaN(); }, "time_step");
  expectRejected([](SimulatorOptions& o) { o.time_step = std::numeric_limits<double>::infinity(); }, "time_step");
  expectRejected([](SimulatorOptions& o) { o.iterations = 0; }, "iterations");
  expectRejected([](SimulatorOptions& o) { o.be_iterations = 0; }, "be_iterations");
  expectRejected([](SimulatorOptions& o) { o.tolerance = -1.0; }, "tolerance");
  expectRejected([](SimulatorOptions& o) { o.energy_tolerance = 0.0; }, "energy_tolerance");
  expectRejected([](SimulatorOptions& o) { o.max_velocity_scale = 0.9; }, "max_velocity_scale");
  expectRejected([](SimulatorOptions& o) { o.max_velocity_scale = std::nan(""); }, "max_velocity_scale");
  expectRejected([](SimulatorOptions& o) { o.chebyshev_rho = 1.0; }, "chebyshev_rho");
  expectRejected([](SimulatorOptions& o) { o.chebyshev_rho = 0.0; }, "chebyshev_rho");
  expectRejected([](SimulatorOptions& o) { o.acceleration = static_cast<Acceleration>(42); }, "acceleration");
  expectRejected([](SimulatorOptions& o) { o.anderson_window = 0; }, "anderson_window");
  expectRejected([](SimulatorOptions& o) { o.max_root_evaluations = 0; }, "max_root_evaluations");
}

TEST(SimulatorInput, BadSceneIsRejectedAndCallerSceneUntouched) {
  Scene s = makeChainPendulum();
  s.masses[3] = -1.0;
  const Scene copy = s;
  EXPECT_THROW(Simulator(s, SimulatorOptions{}), InvalidInputError);
  EXPECT_EQ(s.masses, copy.masses);
  EXPECT_EQ(s.positions, copy.positions);
}

TEST(SimulatorInput, SteppingLeavesTheCallerSceneUntouched) {
  const Scene s = makeChainPendulum();
  Scene mine = s;
  Simulator sim(mine, SimulatorOptions{});
  for (int n = 0; n < 5; ++n) sim.step();
  EXPECT_EQ(mine.positions, s.positions);
  EXPECT_NE(sim.positions(), s.positions);
}

TEST(SimulatorInput, NamesRoundTrip) {
  for (Integrator i : allIntegrators()) EXPECT_EQ(parseIntegrator(integratorName(i)), i);
  EXPECT_EQ(parseIntegrator("bdf2"), Integrator::BDF2);
  EXPECT_THROW(parseIntegrator("RK4"), InvalidInputError);
  EXPECT_EQ(parseBackend("OpenCL"), BackendKind::OpenCL);
  EXPECT_THROW(parseBackend("cuda"), InvalidInputError);
}

}  // namespace
}  // namespace stabint
