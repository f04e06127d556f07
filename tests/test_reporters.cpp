// Per-frame reporters (include/stabint/reporters.hpp): the every-k cadence, the CSV read back
// against the step reports, a throwing reporter (the step stands, ReporterError names it) and a
// refused step (nothing reported).
#include <stabint/stabint.hpp>

#include "temp_dir_test.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace stabint {
namespace {

using ::testing::HasSubstr;
using ReporterTest = testing::TempDirTest;

SimulatorOptions blendOptions() {
  SimulatorOptions o;
  o.integrator = Integrator::EnergyBlend;
  return o;
}

// A reporter that records the step count it saw and the reports it got.
std::shared_ptr<CallbackReporter> recorder(std::vector<StepReport>& reports, std::vector<int>& steps, int every) {
  return std::make_shared<CallbackReporter>(
      [&reports, &steps](const Simulator& sim, const StepReport& r) {
        reports.push_back(r);
        steps.push_back(sim.stepCount());
      },
      every);
}

TEST(Reporters, EachReportsEveryKStepsAfterTheStep) {
  Simulator sim(makeChainPendulum(), blendOptions());
  std::vector<StepReport> r1, r3;
  std::vector<int> s1, s3;
  sim.addReporter(recorder(r1, s1, 1));
  sim.addReporter(recorder(r3, s3, 3));
  for (int n = 0; n < 10; ++n) sim.step();
  EXPECT_EQ(s1, (std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
  EXPECT_EQ(s3, (std::vector<int>{3, 6, 9}));
  ASSERT_EQ(r3.size(), 3u);
  EXPECT_EQ(r3[2].step, 8);
  EXPECT_EQ(r3[2].time, r1[8].time);
  EXPECT_EQ(r1.back().energy.total(), sim.lastReport().energy.total());
}

TEST(Reporters, AddRemoveAndClear) {
  Simulator sim(makeLinearOscillator(), SimulatorOptions{});
  std::vector<StepReport> reports;
  std::vector<int> steps;
  auto a = recorder(reports, steps, 1);
  sim.addReporter(a);
  EXPECT_THROW(sim.addReporter(a), InvalidInputError);
  EXPECT_THROW(sim.addReporter(nullptr), InvalidInputError);
  EXPECT_THROW(CallbackReporter([](const Simulator&, const StepReport&) {}, 0), InvalidInputError);
  EXPECT_THROW(CallbackReporter{CallbackReporter::Function{}}, InvalidInputError);  // braces: not a declaration
  sim.step();
  EXPECT_TRUE(sim.removeReporter(a));
  EXPECT_FALSE(sim.removeReporter(a));
  sim.step();
  EXPECT_EQ(steps, std::vector<int>{1});
  sim.addReporter(a);
  sim.addReporter(std::make_shared<CallbackReporter>([](const Simulator&, const StepReport&) {}));
  EXPECT_EQ(sim.reporters().size(), 2u);
  sim.clearReporters();
  EXPECT_TRUE(sim.reporters().empty());
  sim.step();
  EXPECT_EQ(steps, std::vector<int>{1});
}

std::vector<std::vector<std::string>> readCsv(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream cells_in(line);
    for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

TEST_F(ReporterTest, TheCsvHoldsTheReportsOfTheReportedSteps) {
  Simulator sim(makeClothGrid(), blendOptions());
  const std::string path = (dir_ / "steps.csv").string();
  auto csv = std::make_shared<CsvReporter>(path, 2);
  EXPECT_EQ(csv->name(), "CsvReporter('" + path + "')");
  csv->initialRow(sim);
  sim.addReporter(csv);
  std::vector<StepReport> reports;
  std::vector<int> steps;
  sim.addReporter(recorder(reports, steps, 1));
  const EnergyReport initial = sim.energy();
  for (int n = 0; n < 7; ++n) sim.step();

  const auto rows = readCsv(path);  // flushed row by row: complete while the reporter lives
  ASSERT_EQ(rows.size(), 1u + 1u + 3u);
  EXPECT_EQ(rows[0].size(), 23u);
  EXPECT_EQ(rows[0][0], "frame");
  EXPECT_EQ(rows[0][12], "branch");
  EXPECT_EQ(rows[1][0], "0");
  EXPECT_EQ(std::strtod(rows[1][5].c_str(), nullptr), initial.total());
  for (int k = 0; k < 3; ++k) {
    const StepReport& r = reports[2 * k + 1];  // steps 2, 4, 6 (frames)
    const std::vector<std::string>& row = rows[2 + k];
    ASSERT_EQ(row.size(), 23u);
    const auto number = [&row](int column) { return std::strtod(row[column].c_str(), nullptr); };
    EXPECT_EQ(std::atoi(row[0].c_str()), r.step + 1);
    EXPECT_EQ(number(1), r.time);  // 17 digits: the doubles come back exactly
    EXPECT_EQ(number(2), r.energy.kinetic);
    EXPECT_EQ(number(3), r.energy.elastic);
    EXPECT_EQ(number(4), r.energy.external);
    EXPECT_EQ(number(5), r.energy.total());
    EXPECT_EQ(number(6), r.target);
    EXPECT_EQ(number(7), r.forcing);
    EXPECT_EQ(number(8), r.damping);
    EXPECT_EQ(number(9), r.event_energy);
    EXPECT_EQ(number(10), r.friction);
    EXPECT_EQ(number(11), r.contact_projection);
    EXPECT_EQ(row[12], blendBranchName(r.branch));
    EXPECT_EQ(number(13), r.alpha);
    EXPECT_EQ(number(14), r.velocity_scale);
    EXPECT_EQ(std::atoi(row[15].c_str()), r.iterations);
    EXPECT_EQ(std::atoi(row[16].c_str()), r.energy_evaluations);
    const double times[] = {r.times.local,  r.times.gather, r.times.transfer,
                            r.times.global, r.times.energy, r.times.bookkeeping};
    for (int t = 0; t < 6; ++t) EXPECT_NEAR(number(17 + t), times[t], 1e-8 * times[t] + 1e-300);
  }
  EXPECT_GT(reports[5].iterations, 0);
}

TEST_F(ReporterTest, AFailedCsvWriteIsAFileFormatError) {
  EXPECT_THROW(CsvReporter((dir_ / "missing" / "x.csv").string()), FileFormatError);
  std::ofstream full("/dev/full");
  if (full) {
    EXPECT_THROW(CsvReporter(full, "/dev/full"), FileFormatError);  // the header's flush fails
  }

  // A row that fails after a step: a ReporterError naming the reporter, its cause the
  // FileFormatError; the step stands.
  std::ostringstream out;
  auto csv = std::make_shared<CsvReporter>(out, "memory");
  Simulator sim(makeLinearOscillator(), SimulatorOptions{});
  sim.addReporter(csv);
  sim.step();
  out.setstate(std::ios::badbit);
  try {
    sim.step();
    FAIL() << "the failed write did not propagate";
  } catch (const ReporterError& e) {
    EXPECT_THAT(e.what(), HasSubstr("reporter CsvReporter('memory') failed after step 1 (the step is kept): memory: "
                                    "write failed"));
    EXPECT_THROW(std::rethrow_exception(e.cause()), FileFormatError);
  }
  EXPECT_EQ(sim.stepCount(), 2);
}

TEST(Reporters, AThrowingReporterKeepsTheStepAndNamesItself) {
  Simulator sim(makeChainPendulum(), blendOptions());
  Simulator twin(makeChainPendulum(), blendOptions());
  std::vector<StepReport> after;
  std::vector<int> steps;
  sim.addReporter(std::make_shared<CallbackReporter>(
      [](const Simulator& s, const StepReport&) {
        if (s.stepCount() == 2) throw std::runtime_error("disk on fire");
      },
      1, "fire alarm"));
  sim.addReporter(recorder(after, steps, 1));
  sim.step();
  twin.step();
  try {
    sim.step();
    FAIL() << "the reporter's exception did not propagate";
  } catch (const ReporterError& e) {
    EXPECT_EQ(e.step(), 1);
    EXPECT_THAT(e.what(), HasSubstr("reporter fire alarm failed after step 1"));
    EXPECT_THAT(e.what(), HasSubstr("disk on fire"));
    try {
      std::rethrow_exception(e.cause());
    } catch (const std::runtime_error& cause) {
      EXPECT_STREQ(cause.what(), "disk on fire");
    }
  }
  twin.step();
  // The step stands: the state and count are the twin's, and the reporters after the throwing
  // one were skipped for that step only.
  EXPECT_EQ(sim.stepCount(), 2);
  EXPECT_EQ(sim.lastReport().step, 1);
  EXPECT_TRUE(sim.positions() == twin.positions());
  EXPECT_EQ(steps, std::vector<int>{1});
  sim.step();
  EXPECT_EQ(steps, (std::vector<int>{1, 3}));

  // A stabint::Error from a reporter is wrapped too: it is not a refused step.
  sim.clearReporters();
  sim.addReporter(std::make_shared<CallbackReporter>(
      [](const Simulator&, const StepReport&) { throw NonFiniteStateError("not really", 0); }));
  EXPECT_THROW(sim.step(), ReporterError);
  EXPECT_EQ(sim.stepCount(), 4);
}

TEST(Reporters, ARefusedStepReportsNothing) {
  SimulatorOptions o;
  o.integrator = Integrator::BackwardEuler;
  o.acceleration = Acceleration::None;
  Simulator sim(makeLinearOscillator({1e-20, 1e-20, 1.0}), o);
  std::vector<StepReport> reports;
  std::vector<int> steps;
  sim.addReporter(recorder(reports, steps, 1));
  sim.step();
  sim.setExternalForces(Eigen::MatrixX3d::Constant(sim.positions().rows(), 3, 1e149));
  EXPECT_THROW(sim.step(), NonFiniteStateError);
  EXPECT_EQ(steps, std::vector<int>{1});

  // The energy limit refuses the same way (forward Euler gains energy on the stiff chain).
  SimulatorOptions limited;
  limited.integrator = Integrator::ForwardEuler;
  limited.energy_limit = 10.0;
  Simulator capped(makeChainPendulum(), limited);
  std::vector<StepReport> capped_reports;
  std::vector<int> capped_steps;
  capped.addReporter(recorder(capped_reports, capped_steps, 1));
  bool refused = false;
  for (int n = 0; n < 10000 && !refused; ++n) {
    try {
      capped.step();
    } catch (const EnergyLimitError&) {
      refused = true;
    }
  }
  ASSERT_TRUE(refused);
  ASSERT_GT(capped.stepCount(), 0);
  ASSERT_EQ(static_cast<int>(capped_steps.size()), capped.stepCount());
  EXPECT_EQ(capped_steps.back(), capped.stepCount());
}

}  // namespace
}  // namespace stabint
