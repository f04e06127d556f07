// The OpenCL backend against the CPU reference backend, operation by operation, on random and
// built-in scenes, in double and in float; plus reduction accuracy and determinism.
//
// Tolerances (relative to the largest entry of the reference result, see relativeError):
//   double: 1e-12. Both sides compute the same formulas in IEEE double; they differ only in
//           rounding order (per-vertex gather vs. scattered adds, tree vs. sequential energy
//           sums, FMA contraction in the kernel compiler; the nearest rotation is the same
//           Newton/eigen algorithm on both), each worth a few ulps times small condition numbers
//           of the well-shaped test elements.
//   float:  1e-4 (rhs, forces, dot products) and 1e-3 (energies). Positions are rounded to
//           float (relative 6e-8 of |x| ~ 1) and spring vectors x_a - x_b of length ~0.05 lose
//           about log10(1/0.05) more digits; energies square the stretch |d| - r, which for the
//           ~10 % strains of the test states is ~20x smaller than |d|.
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/simulator.hpp>

#include "cpu/cpu_backend.hpp"
#include "opencl/opencl_backend.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"
#include "test_opencl_support.hpp"
#include "triangle_cloth_scene.hpp"

#include <gtest/gtest.h>

#include <cstdint>

#include <cstring>
#include <memory>
#include <vector>

namespace stabint {
namespace {

using testing::perturbed;
using testing::relativeError;

constexpr int kSlots = 4;

struct Case {
  std::string name;
  Scene scene;
  double noise;  // perturbation of the state around the rest shape
};

std::vector<Case> equivalenceCases() {
  std::vector<Case> cases;
  cases.push_back({"random", testing::randomScene(7, 300, 1500, 400, 12), 0.05});
  cases.push_back({"random_inverting", testing::randomScene(11, 60, 100, 200, 3), 0.4});
  ClothGridParams cloth;
  cloth.nx = 16;
  cloth.ny = 12;
  cases.push_back({"cloth", makeClothGrid(cloth), 0.01});
  cases.push_back({"tet_bar", makeTetBar({}), 0.01});
  cases.push_back({"triangle_cloth", testing::triangleCloth(12, 10), 0.01});
  cases.push_back({"chain", makeChainPendulum({}), 0.02});
  cases.push_back({"oscillator", makeLinearOscillator({}), 0.1});
  return cases;
}

class OpenCLBackendTest : public ::testing::TestWithParam<Precision> {
 protected:
  void SetUp() override { STABINT_SKIP_WITHOUT_OPENCL(GetParam()); }
  Precision precision() const { return GetParam(); }
  double tol() const { return precision() == Precision::Double ? 1e-12 : 1e-4; }
  double energyTol() const { return precision() == Precision::Double ? 1e-12 : 1e-3; }

  // Both backends with slot 0 = x, slot 1 = y (or v), slot 2 = scratch.
  struct Pair {
    std::unique_ptr<SceneData> data;
    std::unique_ptr<Forcing> forcing;
    std::unique_ptr<Backend> cpu, ocl;
  };
  Pair makePair(const Case& c) {
    Pair p;
    p.data = std::make_unique<SceneData>(c.scene);
    p.forcing = std::make_unique<Forcing>(p.data->scene());
    p.cpu = makeCpuBackend(*p.data, *p.forcing, kSlots);
    p.ocl = makeOpenCLBackend(*p.data, *p.forcing, kSlots, testing::openclOptions(precision()));
    const Eigen::MatrixX3d x = perturbed(c.scene.rest_positions, c.noise, 1);
    const Eigen::MatrixX3d y = perturbed(c.scene.rest_positions, c.noise, 2);
    for (Backend* b : {p.cpu.get(), p.ocl.get()}) {
      b->write(0, x);
      b->write(1, y);
    }
    return p;
  }
};

// Backend::traffic counts what crosses the bus, issue 50's measure of a step that stays on the
// device: a write of a slot sends its 3 n reals and a read brings them back; a local step that
// returns its right-hand side (or gradient) brings back 3 n reals and launches the element pass
// and the gather, and with its energy also the per-group partials (3 reals each, as an energy
// pass alone reads them in one launch). The CPU reference counts nothing.
TEST_P(OpenCLBackendTest, TrafficCountsTheBytesAndLaunches) {
  const std::vector<Case> cases = equivalenceCases();
  const Case& c = cases[2];  // the cloth
  Pair p = makePair(c);
  const std::int64_t real = precision() == Precision::Double ? 8 : 4;
  const std::int64_t slot = 3 * real * c.scene.numParticles();
  Backend& b = *p.ocl;
  Backend::Traffic before = b.traffic();
  const auto expect = [&](const char* what, std::int64_t to_device, std::int64_t to_host, std::int64_t launches) {
    const Backend::Traffic& now = b.traffic();
    EXPECT_EQ(now.to_device - before.to_device, to_device) << what;
    EXPECT_EQ(now.to_host - before.to_host, to_host) << what;
    EXPECT_EQ(now.launches - before.launches, launches) << what;
    before = now;
  };
  b.write(0, c.scene.positions);
  expect("write", slot, 0, 0);
  Eigen::MatrixX3d out;
  b.read(0, out);
  expect("read", 0, slot, 0);
  b.localStepRhs(0, 1, 900.0, 0.0, out);  // the first also uploads the forcing where it moves
  before = b.traffic();
  b.localStepRhs(0, 1, 900.0, 0.0, out);
  expect("local step", 0, slot, 2);
  b.localStepGradient(0, 1, 900.0, 0.0, out, nullptr);
  expect("local step's gradient", 0, slot, 2);
  b.potential(0, 0.0);
  const std::int64_t partials = b.traffic().to_host - before.to_host;
  expect("energy pass", 0, partials, 1);
  EXPECT_GT(partials, 0);
  EXPECT_EQ(partials % (3 * real), 0);
  PotentialEnergy energy;
  b.localStepRhs(0, 1, 900.0, 0.0, out, &energy);
  expect("local step with its energy", 0, slot + partials, 2);
  p.cpu->read(0, out);
  p.cpu->localStepRhs(0, 1, 900.0, 0.0, out);
  EXPECT_EQ(p.cpu->traffic().to_device + p.cpu->traffic().to_host + p.cpu->traffic().launches, 0);
}

TEST_P(OpenCLBackendTest, LocalStepRhsMatchesCpu) {
  for (const Case& c : equivalenceCases()) {
    SCOPED_TRACE(c.name);
    Pair p = makePair(c);
    // Several times and step constants: exercises the re-upload of moving pin targets and
    // time-dependent force fields, and the unchanged-time fast path.
    for (double t : {0.0, 0.37, 0.37, 1.25}) {
      for (double cc : {900.0, 3600.0}) {
        Eigen::MatrixX3d ref, got, got_fused;
        p.cpu->localStepRhs(0, 1, cc, t, ref);
        p.ocl->localStepRhs(0, 1, cc, t, got);
        ASSERT_EQ(got.rows(), ref.rows());
        EXPECT_LE(relativeError(got, ref), tol()) << "t = " << t << ", c = " << cc;
        // The fused energy comes from the same launch and the same reduction as potential():
        // bit-identical, and it leaves the right-hand side unchanged.
        PotentialEnergy fused;
        p.ocl->localStepRhs(0, 1, cc, t, got_fused, &fused);
        EXPECT_EQ(std::memcmp(got_fused.data(), got.data(), sizeof(double) * got.size()), 0);
        const PotentialEnergy separate = p.ocl->potential(0, t);
        EXPECT_EQ(fused.internal, separate.internal);
        EXPECT_EQ(fused.pins, separate.pins);
        EXPECT_EQ(fused.external, separate.external);
      }
    }
  }
}

// The objective's gradient from the force form of the pass (gather_gradient): the CPU's order of
// operations, so in double it agrees to round-off; in float to float's round-off of the larger
// terms c M x and c M y it is the difference of (measured against their scale, not the gradient's).
TEST_P(OpenCLBackendTest, LocalStepGradientMatchesCpu) {
  for (const Case& c : equivalenceCases()) {
    SCOPED_TRACE(c.name);
    Pair p = makePair(c);
    for (double t : {0.0, 0.37, 1.25}) {
      for (double cc : {900.0, 3600.0}) {
        Eigen::MatrixX3d ref, got, rhs;
        PotentialEnergy ref_energy, energy;
        p.cpu->localStepGradient(0, 1, cc, t, ref, &ref_energy);
        p.ocl->localStepGradient(0, 1, cc, t, got, &energy);
        p.cpu->localStepRhs(0, 1, cc, t, rhs);
        ASSERT_EQ(got.rows(), ref.rows());
        const double scale = std::max(rhs.cwiseAbs().maxCoeff(), 1e-300);
        EXPECT_LE((got - ref).cwiseAbs().maxCoeff() / scale, tol()) << "t = " << t << ", c = " << cc;
        EXPECT_NEAR(energy.internal, ref_energy.internal, energyTol() * std::max(1.0, std::abs(ref_energy.internal)));
        EXPECT_NEAR(energy.pins, ref_energy.pins, energyTol() * std::max(1.0, std::abs(ref_energy.pins)));
      }
    }
  }
}

TEST_P(OpenCLBackendTest, AccelerationsMatchCpu) {
  for (const Case& c : equivalenceCases()) {
    SCOPED_TRACE(c.name);
    Pair p = makePair(c);
    for (double t : {0.0, 0.8}) {
      Eigen::MatrixX3d ref, got;
      p.cpu->accelerations(2, 0, t);
      p.ocl->accelerations(2, 0, t);
      p.cpu->read(2, ref);
      p.ocl->read(2, got);
      EXPECT_LE(relativeError(got, ref), tol()) << "t = " << t;
    }
  }
}

TEST_P(OpenCLBackendTest, PotentialMatchesCpu) {
  for (const Case& c : equivalenceCases()) {
    SCOPED_TRACE(c.name);
    Pair p = makePair(c);
    for (double t : {0.0, 0.55}) {
      const PotentialEnergy ref = p.cpu->potential(0, t);
      const PotentialEnergy got = p.ocl->potential(0, t);
      // External energy -sum f.x can cancel; judge it against the sum of |f| |x|.
      Eigen::MatrixX3d f, x;
      p.forcing->externalForces(t, f);
      p.cpu->read(0, x);
      const double external_scale = f.cwiseAbs().cwiseProduct(x.cwiseAbs()).sum();
      EXPECT_LE(std::abs(got.internal - ref.internal), energyTol() * std::abs(ref.internal)) << "t = " << t;
      EXPECT_LE(std::abs(got.pins - ref.pins), energyTol() * std::max(std::abs(ref.pins), 1e-300)) << "t = " << t;
      EXPECT_LE(std::abs(got.external - ref.external), energyTol() * external_scale) << "t = " << t;
    }
  }
}

TEST_P(OpenCLBackendTest, MassDotCombineCopyMatchCpu) {
  for (const Case& c : equivalenceCases()) {
    SCOPED_TRACE(c.name);
    Pair p = makePair(c);
    const double ref_dot = p.cpu->massDot(0, 1);
    const double got_dot = p.ocl->massDot(0, 1);
    EXPECT_LE(std::abs(got_dot - ref_dot), tol() * std::abs(ref_dot));
    for (Backend* b : {p.cpu.get(), p.ocl.get()}) {
      b->combine(2, 0.75, 0, -1.5, 1);  // fresh destination
      b->combine(0, 2.0, 0, 0.5, 2);    // destination aliases x
      b->copy(3, 0);
      b->combine(3, 1.0, 3, -0.25, 3);  // all three alias
    }
    for (int slot : {0, 2, 3}) {
      Eigen::MatrixX3d ref, got;
      p.cpu->read(slot, ref);
      p.ocl->read(slot, got);
      EXPECT_LE(relativeError(got, ref), tol()) << "slot " << slot;
    }
    EXPECT_LE(std::abs(p.ocl->massDot(3, 3) - p.cpu->massDot(3, 3)), tol() * p.cpu->massDot(3, 3));
  }
}

TEST_P(OpenCLBackendTest, WriteReadRoundTrip) {
  const Scene scene = makeClothGrid({});
  SceneData data(scene);
  Forcing forcing(data.scene());
  auto ocl = makeOpenCLBackend(data, forcing, 2, testing::openclOptions(precision()));
  const Eigen::MatrixX3d x = perturbed(scene.positions, 0.1, 3);
  ocl->write(1, x);
  Eigen::MatrixX3d back;
  ocl->read(1, back);
  ASSERT_EQ(back.rows(), x.rows());
  if (precision() == Precision::Double)
    EXPECT_EQ(std::memcmp(back.data(), x.data(), sizeof(double) * x.size()), 0);
  else
    EXPECT_TRUE(back.isApprox(x.cast<float>().cast<double>(), 0.0));
  EXPECT_THROW(ocl->read(2, back), InvalidInputError);
  EXPECT_THROW(ocl->write(0, Eigen::MatrixX3d::Zero(3, 3)), InvalidInputError);
}

// Two backends on the same scene, each called twice: every result bit-identical.
TEST_P(OpenCLBackendTest, ResultsAreBitIdenticalAcrossRunsAndInstances) {
  const Case c{"random", testing::randomScene(5, 2000, 20000, 3000, 20), 0.05};
  SceneData data(c.scene);
  Forcing forcing(data.scene());
  auto run = [&](Backend& b) {
    b.write(0, perturbed(c.scene.rest_positions, c.noise, 1));
    b.write(1, perturbed(c.scene.rest_positions, c.noise, 2));
    std::vector<double> out;
    for (int rep = 0; rep < 2; ++rep) {
      Eigen::MatrixX3d rhs, acc;
      b.localStepRhs(0, 1, 3600.0, 0.25, rhs);
      b.accelerations(2, 0, 0.25);
      b.read(2, acc);
      const PotentialEnergy e = b.potential(0, 0.25);
      out.insert(out.end(), rhs.data(), rhs.data() + rhs.size());
      out.insert(out.end(), acc.data(), acc.data() + acc.size());
      out.insert(out.end(), {e.internal, e.pins, e.external, b.massDot(0, 1)});
    }
    return out;
  };
  auto first = makeOpenCLBackend(data, forcing, kSlots, testing::openclOptions(precision()));
  auto second = makeOpenCLBackend(data, forcing, kSlots, testing::openclOptions(precision()));
  const std::vector<double> a = run(*first);
  const std::vector<double> b = run(*second);
  ASSERT_EQ(a.size(), b.size());
  const std::size_t half = a.size() / 2;
  EXPECT_EQ(std::memcmp(a.data(), a.data() + half, half * sizeof(double)), 0) << "call to call";
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0) << "instance to instance";
}

// The tree reduction of 200k spring energies against a compensated sum of the same energies
// computed in double on the host. Double: the tree's error bound is ~log2(N) eps = 4e-15;
// float: per-element energies carry ~1e-6 relative error from float positions.
TEST_P(OpenCLBackendTest, LargeReductionMatchesCompensatedSum) {
  const Scene scene = testing::randomScene(3, 20000, 200000, 0, 0);
  SceneData data(scene);
  Forcing forcing(data.scene());
  auto ocl = makeOpenCLBackend(data, forcing, 1, testing::openclOptions(precision()));
  const Eigen::MatrixX3d x = perturbed(scene.rest_positions, 0.02, 9);
  ocl->write(0, x);
  std::vector<double> energies;
  energies.reserve(scene.springs.size());
  for (const Spring& s : scene.springs) {
    const double stretch = (x.row(s.a) - x.row(s.b)).norm() - s.rest_length;
    energies.push_back(0.5 * s.stiffness * stretch * stretch);
  }
  const double ref = testing::compensatedSum(energies);
  const double got = ocl->potential(0, 0.0).internal;
  EXPECT_LE(std::abs(got - ref), (precision() == Precision::Double ? 1e-13 : 1e-4) * ref)
      << "got " << got << ", compensated " << ref;

  // Mass-weighted dot over 20k particles (partials of the same reduction kernel).
  std::vector<double> terms;
  for (int j = 0; j < x.rows(); ++j) terms.push_back(scene.masses[j] * x.row(j).squaredNorm());
  const double ref_dot = testing::compensatedSum(terms);
  EXPECT_LE(std::abs(ocl->massDot(0, 0) - ref_dot), (precision() == Precision::Double ? 1e-13 : 1e-5) * ref_dot);
}

TEST_P(OpenCLBackendTest, DescriptionNamesDeviceAndPrecision) {
  SceneData data(makeChainPendulum({}));
  Forcing forcing(data.scene());
  auto ocl = makeOpenCLBackend(data, forcing, 1, testing::openclOptions(precision()));
  const std::string d = ocl->description();
  EXPECT_EQ(d.rfind("OpenCL: ", 0), 0u) << d;
  EXPECT_NE(d.find(" / "), std::string::npos) << d;
  EXPECT_NE(d.find(precision() == Precision::Double ? "(double)" : "(float)"), std::string::npos) << d;
}

TEST_P(OpenCLBackendTest, PhaseTimersAccumulate) {
  SceneData data(makeClothGrid({}));
  Forcing forcing(data.scene());
  auto ocl = makeOpenCLBackend(data, forcing, 2, testing::openclOptions(precision()));
  ocl->write(0, data.scene().positions);
  ocl->write(1, data.scene().positions);
  ocl->times() = PhaseTimes{};
  Eigen::MatrixX3d rhs;
  ocl->localStepRhs(0, 1, 900.0, 0.0, rhs);
  ocl->potential(0, 0.0);
  const PhaseTimes& t = ocl->times();
  EXPECT_GT(t.local, 0.0);
  EXPECT_GT(t.gather, 0.0);
  EXPECT_GT(t.transfer, 0.0);
  EXPECT_GT(t.energy, 0.0);
  EXPECT_EQ(t.global, 0.0);
}

INSTANTIATE_TEST_SUITE_P(Precisions, OpenCLBackendTest, ::testing::Values(Precision::Double, Precision::Float),
                         [](const ::testing::TestParamInfo<Precision>& info) {
                           return std::string(precisionName(info.param));
                         });

}  // namespace
}  // namespace stabint
