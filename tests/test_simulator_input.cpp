// Bad options are rejected with an error naming the field, before anything is allocated, and the
// caller's scene is never modified by a Simulator.
#include <stabint/stabint.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <vector>

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
  expectRejected([](SimulatorOptions& o) { o.lbfgs_history = 0; }, "lbfgs_history");
  expectRejected([](SimulatorOptions& o) { o.lbfgs_history = 51; }, "lbfgs_history");
  expectRejected(
      [](SimulatorOptions& o) {
        o.acceleration = Acceleration::Anderson;
        o.gradient_tolerance = 1e-3;
      },
      "gradient_tolerance > 0 needs");
  expectRejected(
      [](SimulatorOptions& o) {
        o.acceleration = Acceleration::LBFGS;
        o.gradient_tolerance = 1.0;
      },
      "gradient_tolerance");
  expectRejected(
      [](SimulatorOptions& o) {
        o.acceleration = Acceleration::LBFGS;
        o.gradient_tolerance = std::nan("");
      },
      "gradient_tolerance");
  expectRejected([](SimulatorOptions& o) { o.max_root_evaluations = 0; }, "max_root_evaluations");
  expectRejected([](SimulatorOptions& o) { o.max_iterations = 0; }, "max_iterations = 0 must be >= 1");
  expectRejected([](SimulatorOptions& o) { o.cg_iterations = -3; }, "cg_iterations = -3 must be >= 1");
  expectRejected([](SimulatorOptions& o) { o.cg_tolerance = 1.0; }, "cg_tolerance = 1 must be finite and in [0, 1)");
  expectRejected([](SimulatorOptions& o) { o.contact_tolerance = -1e-3; }, "contact_tolerance = -0.001");
  expectRejected([](SimulatorOptions& o) { o.contact_tolerance = HUGE_VAL; }, "contact_tolerance = inf");
  expectRejected([](SimulatorOptions& o) { o.anderson_window = 51; }, "anderson_window = 51 must be in [1, 50]");
  expectRejected([](SimulatorOptions& o) { o.global_solve = static_cast<GlobalSolve>(9); }, "global_solve = 9");
}

// Enums from a config file or a binding can hold any integer: an Integrator of 42 used to run no
// integrator and commit a zero state. A finite step whose 1/h^2 overflows (or h^2 underflows)
// used to pass and be reported later as a blow-up.
TEST(SimulatorInput, OutOfRangeEnumsAndOverflowingStepsNameTheField) {
  expectRejected([](SimulatorOptions& o) { o.integrator = static_cast<Integrator>(42); }, "integrator = 42");
  expectRejected([](SimulatorOptions& o) { o.integrator = static_cast<Integrator>(-1); }, "integrator = -1");
  expectRejected([](SimulatorOptions& o) { o.backend = static_cast<BackendKind>(7); }, "backend = 7");
  expectRejected([](SimulatorOptions& o) { o.opencl.precision = static_cast<Precision>(2); }, "opencl.precision = 2");
  expectRejected([](SimulatorOptions& o) { o.time_step = 1e-300; }, "time_step = 1e-300");
  expectRejected([](SimulatorOptions& o) { o.time_step = 1e-160; }, "time_step");
  expectRejected([](SimulatorOptions& o) { o.time_step = 1e200; }, "time_step = 1e+200");
  expectRejected([](SimulatorOptions& o) { o.energy_limit = -1.0; }, "energy_limit");
  expectRejected([](SimulatorOptions& o) { o.energy_limit = std::nan(""); }, "energy_limit");
}

// Forward Euler on the stiff chain gains energy every step until it overflows (about 60 steps).
// With a ceiling the run stops as soon as H exceeds H* by energy_limit * E_scale, refused like a
// non-finite step: the state is the last accepted one, below the ceiling.
TEST(SimulatorInput, EnergyLimitStopsAGainingRunEarly) {
  auto stepsUntilRefused = [](double limit, bool& limited) {
    SimulatorOptions o;
    o.integrator = Integrator::ForwardEuler;
    o.energy_limit = limit;
    Simulator sim(makeChainPendulum(), o);
    for (int n = 0; n < 10000; ++n) {
      try {
        sim.step();
      } catch (const NonFiniteStateError& e) {
        limited = dynamic_cast<const EnergyLimitError*>(&e) != nullptr;
        EXPECT_EQ(e.step(), n);
        EXPECT_EQ(sim.stepCount(), n);  // refused: nothing committed
        EXPECT_TRUE(sim.positions().allFinite());
        if (limited) {
          EXPECT_LE(sim.energy().total() - sim.target(), limit * sim.energyScale());
          EXPECT_NE(std::string(e.what()).find("energy_limit"), std::string::npos) << e.what();
        }
        return n;
      }
    }
    return -1;
  };
  bool limited = false;
  const int overflow = stepsUntilRefused(0.0, limited);
  EXPECT_FALSE(limited);
  ASSERT_GT(overflow, 0);
  const int ceiling = stepsUntilRefused(10.0, limited);
  EXPECT_TRUE(limited);
  EXPECT_GT(ceiling, 0);
  EXPECT_LT(ceiling, overflow);
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

// A Simulator moves (into containers, out of factories) and the moved-to one carries on the same
// trajectory as one that never moved.
TEST(SimulatorMove, MovedSimulatorContinuesTheSameRun) {
  SimulatorOptions o;
  Simulator a(makeChainPendulum(), o);
  Simulator b(makeChainPendulum(), o);
  for (int i = 0; i < 5; ++i) a.step(), b.step();
  std::vector<Simulator> moved;
  moved.push_back(std::move(b));
  moved.emplace_back(makeLinearOscillator(), o);  // may reallocate: moves again
  for (int i = 0; i < 5; ++i) a.step(), moved[0].step();
  EXPECT_EQ(a.stepCount(), moved[0].stepCount());
  EXPECT_EQ((a.positions() - moved[0].positions()).cwiseAbs().maxCoeff(), 0.0);
  Simulator c(makeLinearOscillator(), o);
  c = std::move(moved[0]);
  EXPECT_EQ((a.positions() - c.positions()).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace stabint
