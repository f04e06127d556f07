// The OpenCL side of the batch (docs/batch_design.md): per-scene energies and mass dots of a
// concatenation (Backend::setSegments / potentials / massDots, kernels/segments.cl), checked
// against the single-value reductions and against the CPU reference per scene.
#include <stabint/builders.hpp>

#include "batch_scenes.hpp"
#include "opencl_batch_support.hpp"
#include "test_opencl_support.hpp"

#include "cpu/cpu_backend.hpp"
#include "elements/element_type.hpp"
#include "driver/batch_simulator.hpp"
#include "opencl/opencl_backend.hpp"
#include "scene/scene_batch.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace stabint {
namespace {

using testing::availablePrecisions;
using testing::BatchCase;
using testing::batchOptions;
using testing::crossBackendTolerance;
using testing::expectBookedAndEnergiesNear;
using testing::openclOptions;
using testing::stepBothAndExpectNear;
using testing::typeIndex;

// The same terms summed in another order (a tree per work-group and the groups on the host, or
// one compensated running sum per scene): within a few units of round-off of the sum of the
// terms' magnitudes, whatever their count; these bounds are 10^3-10^4 units (double 1.1e-16,
// float 6e-8), far below any term of the scenes here.
double orderChangeTolerance(Precision p) { return p == Precision::Double ? 1e-12 : 1e-4; }

// sum_j |f_j . x_j| over rows [first, first + count): the size of the external potential's terms,
// against which its error is judged (the sum itself may cancel).
double externalMagnitude(const Forcing& forcing, const Eigen::MatrixX3d& x, double t, int first, int count) {
  Eigen::MatrixX3d f;
  forcing.externalForces(t, f);
  return f.middleRows(first, count).cwiseProduct(x.middleRows(first, count)).rowwise().sum().cwiseAbs().sum();
}

// The mixed scenes concatenated, on an OpenCL backend of `precision` with their segments set.
// With `copies`, the mixed scenes that many times over.
std::vector<Scene> mixedCopies(int copies) {
  std::vector<Scene> scenes;
  for (int copy = 0; copy < copies; ++copy)
    for (const Scene& s : testing::mixedBatchScenes()) scenes.push_back(s);
  return scenes;
}

struct MixedBatchOnDevice {
  explicit MixedBatchOnDevice(Precision precision, int copies = 1)
      : batch(concatenateScenes(mixedCopies(copies))),
        data(batch.scene),
        backend(makeOpenCLBackend(data, forcing, 2, openclOptions(precision))) {
    backend->setSegments(batch.segments);
  }
  const SceneBatch batch;
  const SceneData data;
  Forcing forcing{data.scene()};
  const std::unique_ptr<Backend> backend;
};

// One segment holding the whole scene gives the single-value reductions' numbers, up to the
// order of the additions.
TEST(OpenCLBatch, OneSegmentEqualsTheSingleValueCalls) {
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const SceneBatch batch = concatenateScenes(testing::mixedBatchScenes());
    const SceneBatch whole = concatenateScenes({batch.scene});
    ASSERT_EQ(whole.segments.size(), 1u);
    const SceneData data(batch.scene);
    Forcing forcing(data.scene());
    const std::unique_ptr<Backend> backend = makeOpenCLBackend(data, forcing, 2, openclOptions(precision));
    ASSERT_TRUE(backend->computesPerScene());
    backend->setSegments(whole.segments);
    const Eigen::MatrixX3d x = testing::perturbed(batch.scene.positions, 0.02, 3);
    const Eigen::MatrixX3d v = testing::perturbed(batch.scene.velocities, 0.5, 4);
    backend->write(0, x);
    backend->write(1, v);
    const double tol = orderChangeTolerance(precision);
    for (double t : {0.0, 0.7}) {
      std::vector<PotentialEnergy> per_scene;
      backend->potentials(0, t, per_scene);
      const PotentialEnergy single = backend->potential(0, t);
      ASSERT_EQ(per_scene.size(), 1u);
      EXPECT_GT(single.internal, 0.0);
      EXPECT_GT(single.pins, 0.0);
      EXPECT_NEAR(per_scene[0].internal, single.internal, tol * single.internal) << "t = " << t;
      EXPECT_NEAR(per_scene[0].pins, single.pins, tol * single.pins) << "t = " << t;
      EXPECT_NEAR(per_scene[0].external, single.external,
                  tol * externalMagnitude(forcing, x, t, 0, batch.scene.numParticles()))
          << "t = " << t;
    }
    std::vector<double> dots;
    backend->massDots(1, 1, dots);
    ASSERT_EQ(dots.size(), 1u);
    const double single = backend->massDot(1, 1);
    EXPECT_GT(single, 0.0);
    EXPECT_NEAR(dots[0], single, tol * single);
  }
}

// Each scene's potential and mass dot from the OpenCL batch equal the CPU reference's per-scene
// values (which are each scene's own backend's, tests/test_scene_batch.cpp), to the cross-backend
// tolerance, relative to the size of the scene's terms.
void expectPerSceneEqualsCpu(const Forcing& forcing, const SceneBatch& batch, Backend& opencl, Backend& cpu,
                             const Eigen::MatrixX3d& x, double t, Precision precision) {
  std::vector<PotentialEnergy> got, want;
  opencl.potentials(0, t, got);
  cpu.potentials(0, t, want);
  std::vector<double> got_dots, want_dots;
  opencl.massDots(1, 1, got_dots);
  cpu.massDots(1, 1, want_dots);
  ASSERT_EQ(got.size(), batch.segments.size());
  ASSERT_EQ(want.size(), batch.segments.size());
  ASSERT_EQ(got_dots.size(), batch.segments.size());
  const double tol = crossBackendTolerance(precision);
  for (std::size_t s = 0; s < batch.segments.size(); ++s) {
    const SceneSegment& seg = batch.segments[s];
    SCOPED_TRACE("scene " + std::to_string(s) + ", t = " + std::to_string(t));
    EXPECT_GT(want[s].internal, 0.0);
    EXPECT_NEAR(got[s].internal, want[s].internal, tol * want[s].internal);
    EXPECT_NEAR(got[s].pins, want[s].pins, tol * want[s].pins);
    EXPECT_NEAR(got[s].external, want[s].external,
                tol * externalMagnitude(forcing, x, t, seg.first_particle, seg.num_particles));
    EXPECT_GT(want_dots[s], 0.0);
    EXPECT_NEAR(got_dots[s], want_dots[s], tol * want_dots[s]);
  }
}

TEST(OpenCLBatch, PerSceneValuesEqualTheCpuReferences) {
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const SceneBatch batch = concatenateScenes(testing::mixedBatchScenes());
    const SceneData data(batch.scene);
    Forcing forcing(data.scene());
    const std::unique_ptr<Backend> opencl = makeOpenCLBackend(data, forcing, 2, openclOptions(precision));
    const std::unique_ptr<Backend> cpu = makeCpuBackend(data, forcing, 2);
    opencl->setSegments(batch.segments);
    cpu->setSegments(batch.segments);
    Eigen::MatrixX3d x = testing::perturbed(batch.scene.positions, 0.02, 5);
    Eigen::MatrixX3d v = testing::perturbed(batch.scene.velocities, 0.5, 6);
    opencl->roundToStorage(x);  // both backends see the same numbers
    opencl->roundToStorage(v);
    for (Backend* b : {opencl.get(), cpu.get()}) {
      b->write(0, x);
      b->write(1, v);
    }
    // The chain's field has grown by its rate at t = 0.7; the bar's pins hold at t = 0.
    for (double t : {0.0, 0.7}) expectPerSceneEqualsCpu(forcing, batch, *opencl, *cpu, x, t, precision);
  }
}

// A batch's L-BFGS takes the gradient and every scene's energy from one element pass
// (localStepGradientPerScene): the gradient of localStepGradient and the energies of potentials(),
// bit for bit (the same kernels on the same values; only what the pass also writes differs).
TEST(OpenCLBatch, PerSceneGradientPassIsTheGradientAndThePerScenePass) {
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const MixedBatchOnDevice device(precision);
    const SceneBatch& batch = device.batch;
    Backend* const backend = device.backend.get();
    backend->write(0, testing::perturbed(batch.scene.positions, 0.02, 5));
    backend->write(1, batch.scene.positions);
    const double c = 3600.0;
    for (double t : {0.0, 0.7}) {
      std::vector<PotentialEnergy> fused, pass;
      Eigen::MatrixX3d gradient, alone;
      backend->localStepGradientPerScene(0, 1, c, t, gradient, fused);
      backend->localStepGradient(0, 1, c, t, alone);
      backend->potentials(0, t, pass);
      EXPECT_EQ(gradient, alone) << "t = " << t;
      ASSERT_EQ(fused.size(), batch.segments.size());
      ASSERT_EQ(pass.size(), batch.segments.size());
      for (std::size_t s = 0; s < pass.size(); ++s) {
        EXPECT_GT(pass[s].internal, 0.0) << "scene " << s;
        EXPECT_EQ(fused[s].internal, pass[s].internal) << "scene " << s << ", t = " << t;
        EXPECT_EQ(fused[s].pins, pass[s].pins) << "scene " << s << ", t = " << t;
        EXPECT_EQ(fused[s].external, pass[s].external) << "scene " << s << ", t = " << t;
      }
    }
  }
}

// A pass of some scenes (a batch's solve skipping its stopped scenes, its energy passes of some):
// the element pass then runs over those scenes' work-groups alone, and their energies, gradient
// rows and right-hand-side rows are the whole pass's bit for bit; the entries of the others are
// left as they were. 200 scenes, of which two runs (scenes 30-69 and 150-159) pass: a quarter of
// the scenes, in two launches per element type at most (fewer where the runs share a group).
TEST(OpenCLBatch, PassesOfSomeScenesAreTheirPartOfTheWholePass) {
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const MixedBatchOnDevice device(precision, 50);
    const SceneBatch& batch = device.batch;
    Backend* const backend = device.backend.get();
    std::vector<char> some(batch.segments.size(), 0);
    std::fill(some.begin() + 30, some.begin() + 70, 1);
    std::fill(some.begin() + 150, some.begin() + 160, 1);
    const PotentialEnergy sentinel{1.0, 2.0, 3.0};
    const double c = 3600.0, t = 0.7;
    const Eigen::MatrixX3d x = testing::perturbed(batch.scene.positions, 0.02, 5);
    backend->write(1, batch.scene.positions);
    for (const std::string what : {"gradient", "rhs", "potentials"}) {
      std::vector<PotentialEnergy> all, other, part(some.size(), sentinel);
      Eigen::MatrixX3d whole, rows;
      // The whole pass at x, one at other positions (every element's results then differ), and
      // the pass of some scenes at x again.
      auto pass = [&](const Eigen::MatrixX3d& at, Eigen::MatrixX3d& out, std::vector<PotentialEnergy>& energies,
                      const std::vector<char>* which) {
        backend->write(0, at);
        if (what == "gradient")
          backend->localStepGradientPerScene(0, 1, c, t, out, energies, which);
        else if (what == "rhs")
          backend->localStepRhsPerScene(0, 1, c, t, out, energies, which);
        else
          backend->potentials(0, t, energies, which);
      };
      pass(x, whole, all, nullptr);
      pass(batch.scene.positions, rows, other, nullptr);
      pass(x, rows, part, &some);
      for (std::size_t s = 0; s < some.size(); ++s) {
        const SceneSegment& seg = batch.segments[s];
        if (!some[s]) {
          EXPECT_EQ(part[s].total(), sentinel.total()) << what << ", scene " << s;
          continue;
        }
        EXPECT_NE(other[s].total(), all[s].total()) << what << ", scene " << s;
        EXPECT_EQ(part[s].internal, all[s].internal) << what << ", scene " << s;
        EXPECT_EQ(part[s].pins, all[s].pins) << what << ", scene " << s;
        EXPECT_EQ(part[s].external, all[s].external) << what << ", scene " << s;
        if (what != "potentials") {
          EXPECT_EQ(rows.middleRows(seg.first_particle, seg.num_particles),
                    whole.middleRows(seg.first_particle, seg.num_particles))
              << what << ", scene " << s;
        }
      }
    }
  }
}

// A grab changes the pins block (SceneData::setPins, Backend::elementsChanged): the element
// energies move in the device's layout, and the segments set again afterwards still pick each
// scene's own.
TEST(OpenCLBatch, SegmentsFollowAChangeOfThePins) {
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    SceneBatch batch = concatenateScenes(testing::mixedBatchScenes());
    SceneData data(batch.scene);
    Forcing forcing(data.scene());
    const std::unique_ptr<Backend> opencl = makeOpenCLBackend(data, forcing, 2, openclOptions(precision));
    const std::unique_ptr<Backend> cpu = makeCpuBackend(data, forcing, 2);
    opencl->setSegments(batch.segments);
    // A pin on the last scene's first particle, at the end of the pins block: the last segment's.
    std::vector<Pin> pins = batch.scene.pins;
    Pin grab;
    grab.vertex = batch.segments.back().first_particle;
    grab.stiffness = 1e3;
    grab.target.position = batch.scene.positions.row(grab.vertex).transpose() + Eigen::Vector3d(0.0, 0.1, 0.0);
    pins.push_back(grab);
    data.setPins(pins);
    opencl->elementsChanged();
    cpu->elementsChanged();
    ++batch.segments.back().num_elements[std::size_t(typeIndex("pin"))];
    opencl->setSegments(batch.segments);
    cpu->setSegments(batch.segments);
    Eigen::MatrixX3d x = testing::perturbed(batch.scene.positions, 0.02, 7);
    Eigen::MatrixX3d v = testing::perturbed(batch.scene.velocities, 0.5, 8);
    opencl->roundToStorage(x);
    opencl->roundToStorage(v);
    for (Backend* b : {opencl.get(), cpu.get()}) {
      b->write(0, x);
      b->write(1, v);
    }
    expectPerSceneEqualsCpu(forcing, batch, *opencl, *cpu, x, 0.3, precision);
  }
}

TEST(OpenCLBatch, RefusesSegmentsOutsideTheScene) {
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const MixedBatchOnDevice device(precision);
    const SceneBatch& batch = device.batch;
    Backend* const backend = device.backend.get();
    std::vector<SceneSegment> bad = batch.segments;
    bad.back().num_particles += 1;
    EXPECT_THROW(backend->setSegments(bad), InvalidInputError);
    bad = batch.segments;
    bad[1].num_elements[std::size_t(typeIndex("spring"))] += 1000;
    EXPECT_THROW(backend->setSegments(bad), InvalidInputError);
    // The refused calls left the segments as they were.
    std::vector<double> dots;
    backend->massDots(1, 1, dots);
    EXPECT_EQ(dots.size(), batch.segments.size());
  }
}

// The mixed scenes, then enough small chains that the segments outnumber a work-group of
// segments.cl's per-scene sums, then a cloth whose springs fill several element groups: scenes
// share element groups with their neighbours, and the later ones lie in a later group of sums.
std::vector<Scene> manyScenes() {
  std::vector<Scene> scenes = testing::mixedBatchScenes();
  ChainPendulumParams chain;
  chain.particles = 3;
  for (int i = 0; i < 300; ++i) scenes.push_back(makeChainPendulum(chain));
  ClothGridParams cloth;
  cloth.nx = 14;
  cloth.ny = 12;
  scenes.push_back(makeClothGrid(cloth));
  scenes.push_back(testing::mixedBatchScenes()[0]);
  return scenes;
}

// One scene's input on the device costs its own rows and elements (Backend::writeRows,
// potentialOf; a scene's setState and element changes in a batch): rows written alone replace
// those rows only, as roundToStorage gives them, and one segment's energy is potentials()'s value
// for it bit for bit, whichever segments were evaluated before.
TEST(OpenCLBatch, OneScenesRowsAndPotentialAreItsPartOfTheWholeSlotsAndPass) {
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const SceneBatch batch = concatenateScenes(manyScenes());
    const SceneData data(batch.scene);
    Forcing forcing(data.scene());
    const std::unique_ptr<Backend> backend = makeOpenCLBackend(data, forcing, 2, openclOptions(precision));
    ASSERT_TRUE(backend->writesRows());
    backend->setSegments(batch.segments);
    const Eigen::MatrixX3d x = testing::perturbed(batch.scene.positions, 0.02, 9);
    backend->write(0, x);
    Eigen::MatrixX3d before;
    backend->read(0, before);
    const SceneSegment& seg = batch.segments[2];
    const Eigen::MatrixX3d rows =
        testing::perturbed(batch.scene.positions, 0.03, 10).middleRows(seg.first_particle, seg.num_particles);
    backend->writeRows(0, seg.first_particle, rows);
    Eigen::MatrixX3d after, stored = rows;
    backend->read(0, after);
    backend->roundToStorage(stored);
    EXPECT_EQ(after.middleRows(seg.first_particle, seg.num_particles), stored);
    EXPECT_EQ(after.topRows(seg.first_particle), before.topRows(seg.first_particle));
    const int end = seg.first_particle + seg.num_particles;
    EXPECT_EQ(after.bottomRows(after.rows() - end), before.bottomRows(after.rows() - end));
    EXPECT_THROW(backend->writeRows(0, int(after.rows()) - 1, rows), InvalidInputError);

    // Two slots evaluated in turn: each segment's pass finds the element energies of the other
    // slot's in the groups it shares with its neighbours, and in its own.
    backend->write(1, testing::perturbed(batch.scene.positions, 0.04, 11));
    for (double t : {0.0, 0.7}) {  // the first chain's field has grown by its rate at t = 0.7
      std::vector<PotentialEnergy> all[2];
      for (int slot : {0, 1}) backend->potentials(slot, t, all[slot]);
      ASSERT_EQ(all[0].size(), batch.segments.size());
      for (std::size_t s = batch.segments.size(); s-- > 0;)
        for (int slot : {0, 1}) {
          const PotentialEnergy one = backend->potentialOf(int(s), slot, t);
          const PotentialEnergy& want = all[slot][s];
          EXPECT_EQ(one.internal, want.internal) << "scene " << s << ", slot " << slot << ", t = " << t;
          EXPECT_EQ(one.pins, want.pins) << "scene " << s << ", slot " << slot << ", t = " << t;
          EXPECT_EQ(one.external, want.external) << "scene " << s << ", slot " << slot << ", t = " << t;
        }
      EXPECT_GT(all[0][2].internal, 0.0);
      EXPECT_GT(all[0].back().pins, 0.0);
      // Several segments at once (potentialsOf: their groups merged into fewer launches, one
      // wait): the same values, in the list's order, whatever the list.
      const int count = int(batch.segments.size());
      std::vector<int> every, odd, ends = {count - 1, 0};
      for (int s = count; s-- > 0;) every.push_back(s);
      for (int s = 1; s < count; s += 2) odd.push_back(s);
      for (const std::vector<int>* list : {&every, &odd, &ends})
        for (int slot : {0, 1}) {
          std::vector<PotentialEnergy> some;
          backend->potentialsOf(*list, slot, t, some);
          ASSERT_EQ(some.size(), list->size());
          for (std::size_t i = 0; i < list->size(); ++i) {
            const PotentialEnergy& want = all[slot][std::size_t((*list)[i])];
            EXPECT_EQ(some[i].internal, want.internal) << "scene " << (*list)[i] << ", slot " << slot;
            EXPECT_EQ(some[i].pins, want.pins) << "scene " << (*list)[i] << ", slot " << slot;
            EXPECT_EQ(some[i].external, want.external) << "scene " << (*list)[i] << ", slot " << slot;
          }
        }
    }
    EXPECT_THROW(backend->potentialOf(int(batch.segments.size()), 0, 0.0), InvalidInputError);
    std::vector<PotentialEnergy> none;
    EXPECT_THROW(backend->potentialsOf({0, int(batch.segments.size())}, 0, 0.0, none), InvalidInputError);
  }
}

// potentialsOf over scenes whose per-scene sums lie in several work-groups (300 chains; every
// third scene, from the last): each value is the whole pass's for that scene bit for bit, though
// the sums buffer held another slot's values before.
TEST(OpenCLBatch, SeveralScenesPotentialsAreTheWholePassValues) {
  ChainPendulumParams params;
  params.particles = 4;
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const SceneBatch batch = concatenateScenes(std::vector<Scene>(300, makeChainPendulum(params)));
    const SceneData data(batch.scene);
    Forcing forcing(data.scene());
    const std::unique_ptr<Backend> backend = makeOpenCLBackend(data, forcing, 2, openclOptions(precision));
    backend->setSegments(batch.segments);
    backend->write(0, testing::perturbed(batch.scene.positions, 0.02, 3));
    backend->write(1, testing::perturbed(batch.scene.positions, 0.05, 4));
    std::vector<PotentialEnergy> before, some, want;
    backend->potentials(0, 0.0, before);
    std::vector<int> list;
    for (int s = 299; s >= 0; s -= 3) list.push_back(s);
    backend->potentialsOf(list, 1, 0.0, some);
    backend->potentials(1, 0.0, want);
    ASSERT_EQ(some.size(), list.size());
    for (std::size_t i = 0; i < list.size(); ++i) {
      const PotentialEnergy& w = want[std::size_t(list[i])];
      EXPECT_EQ(some[i].internal, w.internal) << "scene " << list[i];
      EXPECT_EQ(some[i].pins, w.pins) << "scene " << list[i];
      EXPECT_EQ(some[i].external, w.external) << "scene " << list[i];
      EXPECT_NE(w.internal, before[std::size_t(list[i])].internal) << "scene " << list[i];
    }
  }
}

// Element changes (SceneData::setElementStiffness, setElementEnabled) reach the device as the
// changed elements' params alone (ElementBlock::changed_params), or the whole block once more
// changes were made than the log keeps: either way the device then holds what a backend made
// afresh uploads, and every scene's energy is that backend's bit for bit.
TEST(OpenCLBatch, ElementChangesReachTheDeviceAsAFreshUploadWould) {
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const SceneBatch batch = concatenateScenes(manyScenes());
    SceneData data(batch.scene);
    Forcing forcing(data.scene());
    const std::unique_ptr<Backend> backend = makeOpenCLBackend(data, forcing, 1, openclOptions(precision));
    backend->setSegments(batch.segments);
    const Eigen::MatrixX3d x = testing::perturbed(batch.scene.positions, 0.02, 14);
    backend->write(0, x);
    std::vector<PotentialEnergy> got;
    backend->potentials(0, 0.0, got);  // the params are on the device
    const int spring = typeIndex("spring");
    const SceneSegment& cloth = batch.segments[batch.segments.size() - 2];
    const double k = batch.scene.springs[0].stiffness;
    const auto expectAsFresh = [&](const char* what) {
      backend->potentials(0, 0.0, got);
      const std::unique_ptr<Backend> fresh = makeOpenCLBackend(data, forcing, 1, openclOptions(precision));
      fresh->setSegments(batch.segments);
      fresh->write(0, x);
      std::vector<PotentialEnergy> want;
      fresh->potentials(0, 0.0, want);
      for (std::size_t s = 0; s < want.size(); ++s) {
        EXPECT_EQ(got[s].internal, want[s].internal) << what << ", scene " << s;
        EXPECT_EQ(got[s].pins, want[s].pins) << what << ", scene " << s;
      }
    };
    for (int i : {3, 40, 17}) data.setElementStiffness(spring, cloth.first_element[std::size_t(spring)] + i, 3.0 * k);
    data.setElementEnabled(spring, cloth.first_element[std::size_t(spring)] + 5, false);
    expectAsFresh("a few of one scene's springs");
    for (int e = 0; e < 600; ++e) data.setElementStiffness(spring, e, (1.0 + 0.001 * e) * k);
    expectAsFresh("more changes than the log keeps");
  }
}

// A batch of one takes the single-value pass (a Simulator's numbers): so does its one segment.
TEST(OpenCLBatch, TheOneSegmentOfABatchOfOneIsTheSingleValuePass) {
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const SceneBatch whole = concatenateScenes({testing::mixedBatchScenes()[2]});
    const SceneData data(whole.scene);
    Forcing forcing(data.scene());
    const std::unique_ptr<Backend> backend = makeOpenCLBackend(data, forcing, 2, openclOptions(precision));
    backend->setSegments(whole.segments);
    backend->write(0, testing::perturbed(whole.scene.positions, 0.02, 11));
    const PotentialEnergy one = backend->potentialOf(0, 0, 0.0), single = backend->potential(0, 0.0);
    EXPECT_EQ(one.internal, single.internal);
    EXPECT_EQ(one.pins, single.pins);
    EXPECT_EQ(one.external, single.external);
  }
}

// ---- BatchSimulator on OpenCL -------------------------------------------------------------

class OpenCLBatchSimulator : public ::testing::TestWithParam<BatchCase> {};

// The OpenCL batch steps every scene as the CPU batch does (which steps it as its own Simulator,
// tests/test_scene_batch.cpp), to the cross-backend tolerance: positions relative to their size,
// velocities relative to max(max |v|, max |x| / h) as in test_opencl_integrators (the implicit
// integrators' difference quotients turn position rounding eps |x| into eps |x| / h), the
// per-scene energies, target, forcing and damping relative to the scene's E_scale.
TEST_P(OpenCLBatchSimulator, EverySceneFollowsTheCpuBatch) {
  const BatchCase c = GetParam();
  const std::vector<Scene> scenes = testing::mixedBatchScenes();
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const double tol = crossBackendTolerance(precision);
    BatchSimulator opencl(scenes, batchOptions(c, BackendKind::OpenCL, precision));
    BatchSimulator cpu(scenes, batchOptions(c, BackendKind::CpuReference, precision));
    double forcing = 0.0, damping = 0.0;
    for (int step = 0; step < c.steps; ++step) {
      const BatchStepReport& want = stepBothAndExpectNear(opencl, cpu, tol, step);
      for (const StepReport& w : want.scenes) {
        forcing += std::abs(w.forcing);
        damping += w.damping;
      }
    }
    // The chain's growing field does work and the cloth's body is damped: both were compared.
    EXPECT_GT(forcing, 0.0);
    EXPECT_GT(damping, 0.0);
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      SCOPED_TRACE("scene " + std::to_string(s));
      const int i = int(s);
      EXPECT_NEAR(opencl.energyScale(i), cpu.energyScale(i), tol * cpu.energyScale(i));
      // The scene really moved (FE's 20 steps of 1e-5 s fall by g t^2 / 2 = 2e-7 m), so
      // agreement is not two resting states.
      const Eigen::MatrixX3d x = cpu.positions(i), v = cpu.velocities(i);
      ASSERT_GT((x - scenes[s].positions).cwiseAbs().maxCoeff(), 1e-8);
      EXPECT_LE(testing::relativeError(opencl.positions(i), x), tol);
      const double v_scale = std::max(v.cwiseAbs().maxCoeff(), x.cwiseAbs().maxCoeff() / c.time_step);
      EXPECT_LE((opencl.velocities(i) - v).cwiseAbs().maxCoeff(), tol * v_scale);
      EXPECT_EQ(opencl.time(i), cpu.time(i));
      // It ran on the device: a float device's state is floats (the CPU batch's is not).
      if (precision == Precision::Float) {
        EXPECT_TRUE((opencl.positions(i).cast<float>().cast<double>().array() == opencl.positions(i).array()).all());
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Integrators, OpenCLBatchSimulator,
    ::testing::Values(BatchCase{Integrator::SymplecticEuler, 1e-4, 20}, BatchCase{Integrator::ForwardEuler, 1e-5, 20},
                      BatchCase{Integrator::BackwardEuler, 1.0 / 60.0, 20}, BatchCase{Integrator::BDF2, 1.0 / 60.0, 20},
                      BatchCase{Integrator::ImplicitMidpoint, 1.0 / 60.0, 20}),
    [](const ::testing::TestParamInfo<BatchCase>& info) { return std::string(integratorName(info.param.integrator)); });

// L-BFGS in a batch on the device: its per-scene line-search decisions compare objectives that
// agree with the CPU batch's to round-off (double), so every scene takes the same iterates.
TEST(OpenCLBatchSimulator, LbfgsFollowsTheCpuBatch) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  const std::vector<Scene> scenes = testing::mixedBatchScenes();
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend}) {
    SCOPED_TRACE(integratorName(integrator));
    const BatchCase c{integrator, 1.0 / 60.0, 20};
    SimulatorOptions device = batchOptions(c, BackendKind::OpenCL, Precision::Double);
    SimulatorOptions host = batchOptions(c, BackendKind::CpuReference, Precision::Double);
    device.acceleration = host.acceleration = Acceleration::LBFGS;
    BatchSimulator opencl(scenes, device), cpu(scenes, host);
    for (int step = 0; step < c.steps; ++step) {
      const BatchStepReport got = opencl.step();
      const BatchStepReport& want = cpu.step();
      for (std::size_t s = 0; s < scenes.size(); ++s) {
        EXPECT_EQ(got.scenes[s].iterations, want.scenes[s].iterations) << "scene " << s << " step " << step;
        EXPECT_EQ(got.scenes[s].branch, want.scenes[s].branch) << "scene " << s << " step " << step;
      }
    }
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      const Eigen::MatrixX3d x = cpu.positions(int(s));
      ASSERT_GT((x - scenes[s].positions).cwiseAbs().maxCoeff(), 1e-6) << "scene " << s;
      EXPECT_LE(testing::relativeError(opencl.positions(int(s)), x), crossBackendTolerance(Precision::Double))
          << "scene " << s;
    }
  }
}

// ---- the blend on OpenCL ---------------------------------------------------------------------

// The mixed scenes and a stretched chain thrown with random velocities: on these the blend accepts
// IM, blends with the BE partner and scales velocities, mixed within single steps.
std::vector<Scene> blendBatchScenes() {
  std::vector<Scene> scenes = testing::mixedBatchScenes();
  ChainPendulumParams chain;
  chain.particles = 6;
  Scene stretched = makeChainPendulum(chain);
  stretched.positions = testing::perturbed(stretched.positions, 0.05, 11);
  stretched.velocities = testing::perturbed(Eigen::MatrixX3d::Zero(stretched.numParticles(), 3), 2.0, 12);
  scenes.push_back(stretched);
  return scenes;
}

// The blend's IM decision compares |H_IM - H*| with tau = energy_tolerance (K_n + E_int,n +
// E_scale) (docs/method.md section 7). How far a step's decision was from that edge, read from a
// step that accepted IM: its reported H - H* is H_IM - H* at the decision (damping after the
// decision takes the same energy from H and H*; the corrections of an accepted IM candidate leave
// its energy). `previous` is the scene's energy at the step's start.
double distanceFromTheEdge(const StepReport& r, const EnergyReport& previous, double energy_scale,
                           const SimulatorOptions& options) {
  const double tau = options.energy_tolerance * (previous.kinetic + previous.elastic + energy_scale);
  return std::abs(std::abs(r.energy.total() - r.target) - tau);
}

// The OpenCL batch with the blend steps every scene as the CPU batch does (itself each scene's own
// Simulator, tests/test_scene_batch.cpp). In double the energies agree to ~1e-12 of E_scale (measured 3e-12), far
// inside any decision's distance from the tolerance edge: every scene takes the same branch with the same alpha,
// velocity scale and iterations (in float at most the CPU's: a float solve may stop at its round-off floor), and the
// energies, targets and states agree to the cross-backend tolerance (as
// OpenCLBlend.ChainPendulumBranchesAndAlphaMatchCpu for one Simulator). In float the energies carry about 1e-5 of
// E_scale of round-off (measured 8e-6) against a tolerance band of 1e-3 of it, so a decision within that round-off of
// the edge may go either way (the reason crossBackendIntegrators leaves the blend out in float); a scene is compared as
// in double up to its first different branch, which must be such a decision; after it the scene follows its own
// trajectory, of which the blend still holds H within tau of H*. The thrown chain is chaotic: float round-off grows on
// it without any different decision (measured: positions 1e-3 apart at step 14, 4e-3 at step 15, branches the same), so
// in float it is compared over its first 10 steps, as test_opencl_integrators compares float runs over a horizon rather
// than chaos. In double it is compared over 30 steps: L-BFGS's rigid motions resolve its swing about the stiff pin
// (coarse eigenvalues about 7e2 against the pin's 1e6), which amplifies the backends' round-off in the pin's force by
// that ratio (measured: 2e-13 apart after one step, 2e-10 at step 29, then chaos: 1e-8 at step 39; 7e-12 at step 39
// without the rigid motions).
TEST(OpenCLBatchSimulator, BlendFollowsTheCpuBatch) {
  const std::vector<Scene> scenes = blendBatchScenes();
  const BatchCase c{Integrator::EnergyBlend, 1.0 / 60.0, 40};
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const double tol = crossBackendTolerance(precision);
    const SimulatorOptions cpu_options = batchOptions(c, BackendKind::CpuReference, precision);
    BatchSimulator opencl(scenes, batchOptions(c, BackendKind::OpenCL, precision));
    BatchSimulator cpu(scenes, cpu_options);
    // Float: the two runs' energies differ by float round-off (8e-6 of E_scale measured here;
    // orderChangeTolerance's 1e-4 bounds float sums); a decision closer than that to the edge may
    // differ. Double: none may.
    const double edge = precision == Precision::Double ? 0.0 : 1e-4;
    std::vector<EnergyReport> previous_cpu, previous_opencl;
    for (int s = 0; s < int(scenes.size()); ++s) {
      previous_cpu.push_back(cpu.energy(s));
      previous_opencl.push_back(opencl.energy(s));
    }
    std::vector<int> diverged_at(scenes.size(), -1);
    std::vector<int> horizon(scenes.size(), c.steps);
    horizon.back() = precision == Precision::Float ? 10 : 30;  // the thrown chain
    int to_compare = 0;
    for (int h : horizon) to_compare += h;
    std::vector<int> branches(4, 0);
    int compared = 0;
    double worst_energy = 0.0;  // max |H_OpenCL - H_CPU| / E_scale over the compared steps
    for (int step = 0; step < c.steps; ++step) {
      const BatchStepReport got = opencl.step();
      const BatchStepReport& want = cpu.step();
      for (std::size_t s = 0; s < scenes.size(); ++s) {
        SCOPED_TRACE("scene " + std::to_string(s) + " step " + std::to_string(step));
        EXPECT_TRUE(got.refusals[s].empty()) << got.refusals[s];
        EXPECT_TRUE(want.refusals[s].empty()) << want.refusals[s];
        const StepReport& g = got.scenes[s];
        const StepReport& w = want.scenes[s];
        const double scale = cpu.energyScale(int(s));
        // Both runs' tau: each holds H within its tau of its H* (docs/method.md section 7).
        const double tau_band =
            cpu_options.energy_tolerance * (previous_cpu[s].kinetic + previous_cpu[s].elastic + scale) +
            cpu_options.energy_tolerance * (previous_opencl[s].kinetic + previous_opencl[s].elastic + scale);
        if (step >= horizon[s]) continue;
        if (diverged_at[s] < 0 && g.branch != w.branch) {
          // Only a decision within round-off of the edge may differ: the run that accepted IM
          // reports where its decision stood.
          const bool cpu_took_im = w.branch == BlendBranch::ImplicitMidpoint;
          const double distance =
              cpu_took_im ? distanceFromTheEdge(w, previous_cpu[s], scale, cpu_options)
                          : distanceFromTheEdge(g, previous_opencl[s], opencl.energyScale(int(s)), cpu_options);
          ASSERT_TRUE(cpu_took_im || g.branch == BlendBranch::ImplicitMidpoint)
              << "branches " << blendBranchName(g.branch) << " vs " << blendBranchName(w.branch)
              << ": neither accepted IM";
          EXPECT_LE(distance, edge * scale)
              << "branches " << blendBranchName(g.branch) << " (OpenCL) vs " << blendBranchName(w.branch) << " (CPU)";
          diverged_at[s] = step;
          std::printf("  %s: scene %zu takes %s vs %s at step %d, %.3g E_scale from the edge\n",
                      precisionName(precision), s, blendBranchName(g.branch), blendBranchName(w.branch), step,
                      distance / scale);
        }
        previous_cpu[s] = w.energy;
        previous_opencl[s] = g.energy;
        EXPECT_EQ(g.step, w.step);
        EXPECT_EQ(g.time, w.time);
        if (diverged_at[s] >= 0) {
          // Each run on its own trajectory: the targets, moved only by the chain's small forcing
          // and the cloth's damping, stay within the band of each other, and the blend holds
          // each H within its tau of its H*.
          EXPECT_NEAR(g.target, w.target, tau_band);
          EXPECT_NEAR(g.energy.total(), w.energy.total(), 2.0 * tau_band);
          continue;
        }
        ++compared;
        ++branches[std::size_t(w.branch)];
        worst_energy = std::max(worst_energy, std::abs(g.energy.total() - w.energy.total()) / scale);
        // A float solve may stop at its round-off floor before its budget (docs/method.md,
        // "L-BFGS"), where the CPU's double solve goes on.
        if (precision == Precision::Double) {
          EXPECT_EQ(g.iterations, w.iterations);
        } else {
          EXPECT_LE(g.iterations, w.iterations);
        }
        EXPECT_NEAR(g.alpha, w.alpha, precision == Precision::Double ? 1e-8 : tol);
        EXPECT_NEAR(g.velocity_scale, w.velocity_scale, precision == Precision::Double ? 1e-8 : tol);
        expectBookedAndEnergiesNear(g, w, tol * scale);
        const Eigen::MatrixX3d x = cpu.positions(int(s)), v = cpu.velocities(int(s));
        EXPECT_LE(testing::relativeError(opencl.positions(int(s)), x), tol);
        const double v_scale = std::max(v.cwiseAbs().maxCoeff(), x.cwiseAbs().maxCoeff() / c.time_step);
        EXPECT_LE((opencl.velocities(int(s)) - v).cwiseAbs().maxCoeff(), tol * v_scale);
      }
    }
    // Every branch was compared step by step, and most of the run was (a float run that parted
    // at its first steps would compare nothing but bands).
    EXPECT_GT(branches[std::size_t(BlendBranch::ImplicitMidpoint)], 0);
    EXPECT_GT(branches[std::size_t(BlendBranch::BackwardEuler)], 0);
    EXPECT_GT(branches[std::size_t(BlendBranch::VelocityScale)], 0);
    EXPECT_EQ(branches[std::size_t(BlendBranch::None)], 0);
    if (precision == Precision::Double) {
      EXPECT_EQ(compared, to_compare);
    } else {
      EXPECT_GE(compared, to_compare / 2);
    }
    std::printf(
        "  %s: %d of %d scene-steps compared branch for branch (IM %d, BE %d, scale %d), energies within "
        "%.2g E_scale\n",
        precisionName(precision), compared, to_compare, branches[std::size_t(BlendBranch::ImplicitMidpoint)],
        branches[std::size_t(BlendBranch::BackwardEuler)], branches[std::size_t(BlendBranch::VelocityScale)],
        worst_energy);
  }
}

// A scene that blows up is refused at the step the CPU batch refuses it, with the same reason, and
// keeps its last state; its neighbour steps on as on the CPU.
// The batch makes the backend the options ask for, with its errors.
TEST(OpenCLBatchSimulator, MakesTheOpenCLBackendTheOptionsAskFor) {
  SimulatorOptions options = batchOptions({Integrator::BackwardEuler, 0.01, 1}, BackendKind::OpenCL, Precision::Float);
  options.opencl.platform = "no such platform";
  EXPECT_THROW(BatchSimulator(testing::mixedBatchScenes(), options), NoOpenCLDeviceError);
}

TEST(OpenCLBatchSimulator, RefusesTheSceneTheCpuBatchRefuses) {
  ChainPendulumParams soft, stiff;
  soft.stiffness = 10.0;
  soft.pin_stiffness = 100.0;  // SE stable at h = 1e-3 (omega about 90/s)
  stiff.particles = 6;         // pin omega about 7,700/s: SE explodes at h = 1e-3
  const std::vector<Scene> scenes = {makeChainPendulum(soft), makeChainPendulum(stiff)};
  const BatchCase c{Integrator::SymplecticEuler, 1e-3, 200};
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    SimulatorOptions options = batchOptions(c, BackendKind::OpenCL, precision);
    options.energy_limit = 1.0;
    BatchSimulator opencl(scenes, options);
    options.backend = BackendKind::CpuReference;
    BatchSimulator cpu(scenes, options);
    int refused_at = -1;
    for (int step = 0; step < c.steps; ++step) {
      const BatchStepReport got = opencl.step();
      const BatchStepReport& want = cpu.step();
      EXPECT_TRUE(got.refusals[0].empty()) << got.refusals[0];
      ASSERT_EQ(got.refusals[1].empty(), want.refusals[1].empty()) << "step " << step << ": " << want.refusals[1];
      if (!want.refusals[1].empty() && refused_at < 0) {
        refused_at = step;
        // The same reason at the same step; the figures after it are each backend's energies.
        const std::string reason = want.refusals[1].substr(0, want.refusals[1].find("H = "));
        EXPECT_EQ(got.refusals[1].substr(0, reason.size()), reason);
        EXPECT_NE(reason.find("energy"), std::string::npos) << want.refusals[1];
      }
    }
    ASSERT_GE(refused_at, 1) << "the stiff chain never exceeded the limit";
    const double tol = crossBackendTolerance(precision);
    EXPECT_FALSE(opencl.active(1));
    EXPECT_EQ(opencl.stepCount(1), cpu.stepCount(1));
    EXPECT_LE(testing::relativeError(opencl.positions(1), cpu.positions(1)), tol);
    EXPECT_NEAR(opencl.target(1), cpu.target(1), tol * cpu.energyScale(1));
    EXPECT_TRUE(opencl.active(0));
    EXPECT_LE(testing::relativeError(opencl.positions(0), cpu.positions(0)), tol);
    const double v_scale =
        std::max(cpu.velocities(0).cwiseAbs().maxCoeff(), cpu.positions(0).cwiseAbs().maxCoeff() / c.time_step);
    EXPECT_LE((opencl.velocities(0) - cpu.velocities(0)).cwiseAbs().maxCoeff(), tol * v_scale);
  }
}

// ---- colliders on OpenCL ---------------------------------------------------------------------

// The contact batch (three scenes in one space, each scene's colliders on its own particles only:
// tests/test_batch_contact.cpp) steps on the device as the CPU batch does, to the cross-backend
// tolerance of the contact tests (test_opencl_contact.cpp): positions relative to their size,
// friction, the contact projection, target and energies relative to the scene's E_scale, for the
// integrators those tests compare across backends. The device's contact pass runs over the
// concatenation's pairs, which are each scene's own.
TEST(OpenCLBatchSimulator, ContactFollowsTheCpuBatch) {
  const std::vector<Scene> scenes = testing::contactBatchScenes();
  for (Precision precision : availablePrecisions()) {
    const double tol = crossBackendTolerance(precision);
    for (Integrator integrator : testing::crossBackendIntegrators(precision)) {
      SCOPED_TRACE(std::string(precisionName(precision)) + " " + integratorName(integrator));
      const BatchCase c{integrator, 1.0 / 60.0, 40};
      BatchSimulator opencl(scenes, batchOptions(c, BackendKind::OpenCL, precision));
      BatchSimulator cpu(scenes, batchOptions(c, BackendKind::CpuReference, precision));
      std::vector<double> friction(scenes.size(), 0.0);
      for (int step = 0; step < c.steps; ++step) {
        const BatchStepReport& want = stepBothAndExpectNear(opencl, cpu, tol, step);
        for (std::size_t s = 0; s < scenes.size(); ++s) {
          EXPECT_LT(testing::relativeError(opencl.positions(int(s)), cpu.positions(int(s))), tol)
              << "scene " << s << " step " << step;
          friction[s] += want.scenes[s].friction;
        }
      }
      EXPECT_GT(friction[0], 0.0) << "the first cloth must reach its colliders within the run";
      EXPECT_GT(friction[2], 0.0) << "the bar must slide on its ground";
    }
  }
}

// CG in a device batch runs on the host, on each scene's block (GlobalSystem::setBlocks): the
// device's CG reduces over the whole system. Each scene follows its own device Simulator, whose CG
// runs on the device (the same algorithm: Jacobi-preconditioned, warm-started, fixed count or
// tolerance), to the cross-backend tolerance, in double and float.
TEST(OpenCLBatchSimulator, ConjugateGradientsArePerScene) {
  const std::vector<Scene> scenes = testing::mixedBatchScenes();
  for (Precision precision : availablePrecisions())
    for (const double cg_tolerance : {0.0, 1e-6}) {
      SCOPED_TRACE(precisionName(precision) + std::string(", CG tolerance ") + std::to_string(cg_tolerance));
      SimulatorOptions options =
          batchOptions(BatchCase{Integrator::BackwardEuler, 1.0 / 60.0, 8}, BackendKind::OpenCL, precision);
      options.global_solve = GlobalSolve::ConjugateGradient;
      options.cg_tolerance = cg_tolerance;
      BatchSimulator batch(scenes, options);
      std::vector<Simulator> alone;
      for (const Scene& s : scenes) alone.emplace_back(s, options);
      const double tol = crossBackendTolerance(precision, options.acceleration);
      for (int step = 0; step < 8; ++step) {
        const BatchStepReport& report = batch.step();
        for (std::size_t s = 0; s < scenes.size(); ++s) {
          SCOPED_TRACE("scene " + std::to_string(s) + " step " + std::to_string(step));
          const StepReport& own = alone[s].step();
          EXPECT_TRUE(report.refusals[s].empty()) << report.refusals[s];
          // In float L-BFGS may meet its round-off floor at another iteration with the host's CG
          // in double than with the device's in float.
          if (precision == Precision::Double) {
            EXPECT_EQ(report.scenes[s].iterations, own.iterations);
          }
          expectBookedAndEnergiesNear(report.scenes[s], own, tol * alone[s].energyScale());
          EXPECT_LE(testing::relativeError(batch.positions(int(s)), alone[s].positions()), tol);
        }
      }
    }
}

// Stops by accuracy on the device are per scene as on the CPU reference
// (BatchSimulator.StopsByAccuracyArePerScene): each scene of the device batch takes the
// iterations its own device Simulator takes, step by step, and follows its trajectory (the
// solver's decisions are the host's, on the device's per-scene objectives: the projection pass's
// per-scene energies for Chebyshev and Anderson, Backend::localStepRhsPerScene), the tolerance
// stop of every solver, in double and float; the scenes stop at different counts.
TEST(OpenCLBatchSimulatorStops, StopsByAccuracyArePerScene) {
  const std::vector<Scene> scenes = testing::mixedBatchScenes();
  for (Precision precision : availablePrecisions())
    for (Acceleration acceleration : {Acceleration::LBFGS, Acceleration::None, Acceleration::Chebyshev,
                                      Acceleration::Anderson, Acceleration::Newton}) {
      SCOPED_TRACE(precisionName(precision) + std::string(", ") + accelerationName(acceleration));
      SimulatorOptions options =
          batchOptions(BatchCase{Integrator::EnergyBlend, 1.0 / 60.0, 8}, BackendKind::OpenCL, precision);
      options.acceleration = acceleration;
      options.tolerance = precision == Precision::Float ? 1e-5 : 1e-7;
      options.max_iterations = 60;
      BatchSimulator batch(scenes, options);
      std::vector<Simulator> alone;
      for (const Scene& s : scenes) alone.emplace_back(s, options);
      int steps_with_different_counts = 0;
      for (int step = 0; step < 8; ++step) {
        const BatchStepReport& report = batch.step();
        int fewest = report.scenes[0].iterations, most = fewest;
        for (std::size_t s = 0; s < scenes.size(); ++s) {
          SCOPED_TRACE("scene " + std::to_string(s) + " step " + std::to_string(step));
          const StepReport& own = alone[s].step();
          EXPECT_TRUE(report.refusals[s].empty()) << report.refusals[s];
          EXPECT_EQ(report.scenes[s].iterations, own.iterations);
          EXPECT_EQ(report.scenes[s].branch, own.branch);
          expectBookedAndEnergiesNear(report.scenes[s], own, crossBackendTolerance(precision) * alone[s].energyScale());
          EXPECT_LE(testing::relativeError(batch.positions(int(s)), alone[s].positions()),
                    crossBackendTolerance(precision));
          fewest = std::min(fewest, report.scenes[s].iterations);
          most = std::max(most, report.scenes[s].iterations);
        }
        if (fewest < most) ++steps_with_different_counts;
      }
      EXPECT_GT(steps_with_different_counts, 0);
    }
}

}  // namespace
}  // namespace stabint
