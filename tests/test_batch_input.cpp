// Per-frame input of a batch (docs/method.md, "Batches"; include/stabint/batch.hpp): input given
// to one scene makes that scene follow its own Simulator given the same input, step by step
// (state, energies, target, forcing and events), while the other scenes follow their own
// Simulators, which get none; bad input names the call, the scene and the index, and changes
// nothing. The standard is the batch tests' (batch_scenes.hpp): states to 1e-9 of the scene's
// size, energies and what a step books to 1e-12 of the scene's E_scale, the same branches. Where
// pins or element weights change, the batch's one factor is updated or refactored where each
// scene's own is, but an update of one scene's block changes the arithmetic of the whole factor
// (cholmod_updown turns it into an LDL' factor; a refactorization is of the whole batch), so the
// scenes differ from their own Simulators by round-off from then on: here by less than 1e-13 of
// E_scale after grabs and up to a few 1e-13 after element changes. (A stiffer scene amplifies such round-off
// more: the pinned chain of mixedBatchScenes, a 1e6 N/m pin on 12.5 g, moves by 1.6e-12 of its
// E_scale in 45 BE steps when its own Simulator's factor gets an update and a downdate that leave
// L as it was.)
#include <stabint/batch.hpp>
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/simulator.hpp>

#include "batch_scenes.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace stabint {
namespace {

using testing::contactBatchScenes;
using testing::mixedBatchScenes;
using testing::stepAndExpectSame;

// A chain without pins released with its links stretched by about `stretch` and moving at about
// `speed`: it conserves momentum until it is pushed or grabbed.
Scene freeChain(double stiffness, double stretch, double speed) {
  ChainPendulumParams params;
  params.particles = 6;
  params.stiffness = stiffness;
  Scene chain = makeChainPendulum(params);
  chain.pins.clear();
  for (int j = 0; j < chain.numParticles(); ++j)
    for (int k = 0; k < 3; ++k) {
      chain.positions(j, k) += stretch * std::sin(1.7 * j + 2.3 * k + 0.4);
      chain.velocities(j, k) = speed * std::sin(1.3 * j - 0.7 * k);
    }
  return chain;
}

// Three different scenes: a soft free chain, the damped cloth with its two pinned corners, the tet
// bar with its pinned end. Input to the first two moves the pins of the later ones in the batch's
// pin list.
std::vector<Scene> inputScenes() {
  const std::vector<Scene> mixed = mixedBatchScenes();
  return {freeChain(1e2, 0.01, 0.5), mixed[1], mixed[2]};
}

SimulatorOptions inputOptions(Integrator integrator) {
  SimulatorOptions options;
  options.integrator = integrator;
  options.time_step = 1.0 / 60.0;
  options.iterations = 5;
  return options;
}

// The batch of `scenes` and each scene's own Simulator.
struct BatchAndOwn {
  BatchAndOwn(const std::vector<Scene>& scenes, const SimulatorOptions& options) : batch(scenes, options) {
    for (const Scene& s : scenes) alone.emplace_back(s, options);
  }
  /// One step of both, compared (stepAndExpectSame).
  const BatchStepReport& step(int step) { return stepAndExpectSame(batch, alone, "step " + std::to_string(step)); }
  BatchSimulator batch;
  std::vector<Simulator> alone;
};

// A per-particle force that changes from frame to frame (newtons, about the weight of the
// particles of these scenes).
Eigen::MatrixX3d gust(int particles, int frame, double size) {
  Eigen::MatrixX3d f(particles, 3);
  for (int j = 0; j < particles; ++j)
    f.row(j) << size * std::sin(0.3 * frame + j), 0.5 * size, size * std::cos(0.2 * frame - 0.5 * j);
  return f;
}

class BatchInput : public ::testing::TestWithParam<Integrator> {};

// Forces set every frame on the free chain (in some frames twice) and, in some of the same frames,
// on the cloth follow each scene's own Simulator given the same forces; the bar, given none,
// follows its own. The forces then persist. (That a pushed scene stops conserving momentum for the blend is
// BatchInputBlend's.)
TEST_P(BatchInput, ExternalForcesActOnTheirSceneOnly) {
  const std::vector<Scene> scenes = inputScenes();
  BatchAndOwn both(scenes, inputOptions(GetParam()));
  std::vector<double> work(scenes.size(), 0.0);
  for (int step = 0; step < 40; ++step) {
    if (step < 30) {
      const Eigen::MatrixX3d chain = gust(scenes[0].numParticles(), step, 0.05);
      if (step % 4 == 1) {  // set twice in one frame: the second call's forces are the step's
        const Eigen::MatrixX3d first = -2.0 * chain;
        both.batch.setExternalForces(0, first);
        both.alone[0].setExternalForces(first);
      }
      both.batch.setExternalForces(0, chain);
      both.alone[0].setExternalForces(chain);
    }
    if (step >= 10 && step < 30 && step % 3 == 0) {
      const Eigen::MatrixX3d cloth = gust(scenes[1].numParticles(), step, 0.02);
      both.batch.setExternalForces(1, cloth);
      both.alone[1].setExternalForces(cloth);
    }
    const BatchStepReport& report = both.step(step);
    for (std::size_t s = 0; s < scenes.size(); ++s) work[s] += std::abs(report.scenes[s].forcing);
  }
  EXPECT_GT(work[0], 0.0);
  EXPECT_GT(work[1], 0.0);
}

// A box dragged along a path by setColliderPosition in one scene and a ground lifted and stopped
// by setColliderVelocity in another push their own scenes only, each as its own Simulator given
// the same calls; the getters report what the scene's own Simulator reports, bit for bit.
TEST_P(BatchInput, ColliderMotionActsOnItsSceneOnly) {
  const std::vector<Scene> scenes = contactBatchScenes();
  BatchAndOwn both(scenes, inputOptions(GetParam()));
  const int box = 2, ground = 0;  // scene 0's box (clothOnColliders), scene 2's ground
  ASSERT_EQ(scenes[0].colliders[box].shape, ColliderShape::Box);
  double work = 0.0;
  for (int step = 0; step < 40; ++step) {
    const Eigen::Vector3d p =
        scenes[0].colliders[box].center + Eigen::Vector3d(0.02 * step, 0.1 * std::sin(0.2 * step), 0.0);
    both.batch.setColliderPosition(0, box, p);
    both.alone[0].setColliderPosition(box, p);
    if (step == 10 || step == 20) {
      const Eigen::Vector3d v(0.0, step == 10 ? 0.2 : 0.0, 0.0);
      both.batch.setColliderVelocity(2, ground, v);
      both.alone[2].setColliderVelocity(ground, v);
    }
    const BatchStepReport& report = both.step(step);
    work += std::abs(report.scenes[0].forcing) + std::abs(report.scenes[2].forcing);
    for (int s : {0, 2})
      for (int c = 0; c < int(scenes[std::size_t(s)].colliders.size()); ++c) {
        EXPECT_EQ(both.batch.colliderPosition(s, c), both.alone[std::size_t(s)].colliderPosition(c));
        EXPECT_EQ(both.batch.colliderVelocity(s, c), both.alone[std::size_t(s)].colliderVelocity(c));
      }
  }
  EXPECT_GT(work, 0.0);
  // The ground was lifted by 0.2 m/s for ten steps, then stopped.
  EXPECT_NEAR(both.batch.colliderPosition(2, ground).y(), scenes[2].colliders[ground].center.y() + 0.2 * 10 / 60.0,
              1e-12);
  EXPECT_EQ(both.batch.colliderVelocity(2, ground), Eigen::Vector3d::Zero());
}

// Grabs, drags and releases in the first two scenes, while a pin of the bar is dragged every frame
// and one of the cloth's pins is disabled: the pins after a grab move in the batch's pin list, and
// their ramps and flags go with them. Every scene follows its own Simulator given the same calls;
// grab returns the index its own Simulator returns.
TEST_P(BatchInput, GrabAndReleaseAreEventsOfTheirScene) {
  const std::vector<Scene> scenes = inputScenes();
  BatchAndOwn both(scenes, inputOptions(GetParam()));
  BatchSimulator& batch = both.batch;
  std::vector<Simulator>& alone = both.alone;
  const Eigen::Vector3d bar_pin = scenes[2].pins[0].target.position;
  int chain_handle = -1, cloth_handle = -1;
  Eigen::Vector3d chain_grabbed_at = Eigen::Vector3d::Zero();
  std::vector<double> events(scenes.size(), 0.0);
  for (int step = 0; step < 50; ++step) {
    const Eigen::Vector3d q = bar_pin + Eigen::Vector3d(0.0, 0.0005 * step, 0.0);
    batch.setPinTarget(2, 0, q);
    alone[2].setPinTarget(0, q);
    if (step == 4) {
      batch.setElementEnabled(1, ElementKind::Pin, 1, false);
      alone[1].setElementEnabled(ElementKind::Pin, 1, false);
    }
    if (step == 8) {
      chain_handle = batch.grab(0, 5, 2e3);
      EXPECT_EQ(chain_handle, alone[0].grab(5, 2e3));
      chain_grabbed_at = batch.positions(0).row(5).transpose();
    }
    if (step > 8 && step < 30) {
      const Eigen::Vector3d hand = chain_grabbed_at + Eigen::Vector3d(0.0, 0.01 * (step - 8), 0.005 * (step - 8));
      batch.setPinTarget(0, chain_handle, hand);
      alone[0].setPinTarget(chain_handle, hand);
    }
    if (step == 30) {
      batch.release(0, chain_handle);
      alone[0].release(chain_handle);
    }
    if (step == 34) {
      cloth_handle = batch.grab(1, 12, 5e2);
      EXPECT_EQ(cloth_handle, alone[1].grab(12, 5e2));
    }
    if (step == 42) {
      batch.release(1, 0);  // a pin of the scene itself
      alone[1].release(0);
    }
    const BatchStepReport& report = both.step(step);
    for (std::size_t s = 0; s < scenes.size(); ++s) events[s] += std::abs(report.scenes[s].event_energy);
    for (std::size_t s = 1; s < scenes.size(); ++s)
      for (int pin = 0; pin < int(alone[s].scene().pins.size()); ++pin) {
        // A grabbed pin's target is where its particle was, which agrees to the state's round-off.
        EXPECT_LT((batch.pinTarget(int(s), pin) - alone[s].pinTarget(pin)).cwiseAbs().maxCoeff(), 1e-12)
            << "scene " << s << " pin " << pin;
        EXPECT_EQ(batch.elementEnabled(int(s), ElementKind::Pin, pin), alone[s].elementEnabled(ElementKind::Pin, pin));
      }
  }
  EXPECT_EQ(chain_handle, 0);
  EXPECT_EQ(cloth_handle, 2);
  EXPECT_FALSE(batch.elementEnabled(1, ElementKind::Pin, 1));
  // The releases were events of their scenes (the bar's drag is forcing, no event).
  EXPECT_GT(events[0], 0.0);
  EXPECT_GT(events[1], 0.0);
  EXPECT_EQ(events[2], 0.0);
}

// Stiffness changes and disabled elements in each scene, a single element, a short list (rank
// updates of the factor) and a list of more than 64 columns (a refactorization of the whole
// factor), each an event of its scene as in its own Simulator.
TEST_P(BatchInput, ElementChangesAreEventsOfTheirScene) {
  const std::vector<Scene> scenes = inputScenes();
  BatchAndOwn both(scenes, inputOptions(GetParam()));
  BatchSimulator& batch = both.batch;
  std::vector<Simulator>& alone = both.alone;
  ASSERT_GE(scenes[1].springs.size(), 70u);
  std::vector<int> many_springs;
  for (int i = 0; i < 70; ++i) many_springs.push_back(i);
  const std::vector<int> tets = {0, 1, 2};
  const double spring_k = scenes[1].springs[3].stiffness;
  const std::vector<std::function<void()>> changes = {
      [&] {
        batch.setElementStiffness(1, ElementKind::Spring, 3, 0.1 * spring_k);
        alone[1].setElementStiffness(ElementKind::Spring, 3, 0.1 * spring_k);
      },
      [&] {
        batch.setElementEnabled(2, ElementKind::Tet, tets, false);
        alone[2].setElementEnabled(ElementKind::Tet, tets, false);
      },
      [&] {
        batch.setElementStiffness(1, ElementKind::Spring, many_springs, 2.0 * spring_k);
        alone[1].setElementStiffness(ElementKind::Spring, many_springs, 2.0 * spring_k);
      },
      [&] {
        batch.setElementStiffness(0, ElementKind::Spring, 2, 0.2 * scenes[0].springs[2].stiffness);
        alone[0].setElementStiffness(ElementKind::Spring, 2, 0.2 * scenes[0].springs[2].stiffness);
      },
      [&] {
        batch.setElementEnabled(2, ElementKind::Tet, tets, true);
        alone[2].setElementEnabled(ElementKind::Tet, tets, true);
      },
      [&] {
        batch.setElementStiffness(2, ElementKind::Pin, 0, 1e5);
        alone[2].setElementStiffness(ElementKind::Pin, 0, 1e5);
      },
      [&] {
        batch.setElementEnabled(0, ElementKind::Spring, 0, false);
        alone[0].setElementEnabled(ElementKind::Spring, 0, false);
      },
  };
  std::vector<double> events(scenes.size(), 0.0);
  for (int step = 0; step < 50; ++step) {
    if (step % 6 == 3 && std::size_t(step / 6) < changes.size()) changes[std::size_t(step / 6)]();
    const BatchStepReport& report = both.step(step);
    for (std::size_t s = 0; s < scenes.size(); ++s) events[s] += std::abs(report.scenes[s].event_energy);
  }
  for (std::size_t s = 0; s < scenes.size(); ++s) EXPECT_GT(events[s], 0.0) << "scene " << s;
  EXPECT_FALSE(batch.elementEnabled(0, ElementKind::Spring, 0));
  EXPECT_TRUE(batch.elementEnabled(2, ElementKind::Tet, 1));
}

INSTANTIATE_TEST_SUITE_P(Integrators, BatchInput,
                         ::testing::Values(Integrator::BackwardEuler, Integrator::BDF2, Integrator::ImplicitMidpoint,
                                           Integrator::EnergyBlend),
                         [](const ::testing::TestParamInfo<Integrator>& info) {
                           return std::string(integratorName(info.param));
                         });

// The blend keeps a scene's momenta while the scene conserves them (no pins, fields, colliders or
// user forces) and stops once input makes it not: stiff free chains, released stretched, whose IM
// candidates gain energy so that the blend corrects them, one pushed from step 5 on, one grabbed
// at step 5 and held. Each follows its own Simulator given the same input, the corrections
// included.
TEST(BatchInputBlend, InputEndsASceneConservingMomentumAsInItsOwnSimulator) {
  const std::vector<Scene> scenes = {freeChain(1e4, 0.05, 2.0), freeChain(1e4, 0.04, 1.5), mixedBatchScenes()[1]};
  BatchAndOwn both(scenes, inputOptions(Integrator::EnergyBlend));
  std::vector<int> corrected(scenes.size(), 0);
  for (int step = 0; step < 30; ++step) {
    if (step >= 5) {
      const Eigen::MatrixX3d push = gust(scenes[0].numParticles(), step, 0.05);
      both.batch.setExternalForces(0, push);
      both.alone[0].setExternalForces(push);
    }
    if (step == 5) {
      EXPECT_EQ(both.batch.grab(1, 2, 1e3), both.alone[1].grab(2, 1e3));
    }
    const BatchStepReport& report = both.step(step);
    for (std::size_t s = 0; s < scenes.size(); ++s)
      if (step >= 5 && report.scenes[s].branch != BlendBranch::ImplicitMidpoint) ++corrected[s];
  }
  EXPECT_GT(corrected[0], 0);
  EXPECT_GT(corrected[1], 0);
}

// A hand drags a cloth corner with a budget of 30 iterations, where the blend's partner often
// cannot reach the target whole and goes on (BatchDriver::extendPartner, for that scene only):
// the dragged cloth and the scenes beside it each follow their own Simulator.
TEST(BatchInputBlend, APartnerThatGoesOnStepsAsInItsOwnSimulator) {
  const Scene cloth = makeClothGrid(ClothGridParams{});
  const int corner = cloth.numParticles() - 1;
  // (Beside it scenes that do not amplify round-off: the grab updates the batch's one factor, so the
  // scenes differ from their own Simulators by round-off from then on, file comment.)
  const std::vector<Scene> scenes = {mixedBatchScenes()[1], cloth, mixedBatchScenes()[2]};
  SimulatorOptions options;
  options.iterations = 30;
  BatchAndOwn both(scenes, options);
  const int hand = both.batch.grab(1, corner, 1e4);
  EXPECT_EQ(hand, both.alone[1].grab(corner, 1e4));
  const Eigen::Vector3d start = cloth.positions.row(corner).transpose(), up(1.0, 0.2, 0.4);
  int went_on = 0;
  for (int step = 0; step < 30; ++step) {
    const double s = (step + 1) / 30.0;
    const Eigen::Vector3d target = (1 - s) * start + s * up;
    both.batch.setPinTarget(1, hand, target);
    both.alone[1].setPinTarget(hand, target);
    const BatchStepReport& report = both.step(step);
    // The IM candidate's 30 and the partner's 3 iterations, and 27 more where it went on.
    went_on += report.scenes[1].iterations > options.iterations + options.be_iterations ? 1 : 0;
  }
  EXPECT_GT(went_on, 0) << "no step of the dragged cloth took the longer partner";
}

// Everything a refused call could have changed: every scene's state, time, target, energies, pin
// targets and pin flags.
struct Snapshot {
  explicit Snapshot(const BatchSimulator& batch) {
    for (int s = 0; s < batch.size(); ++s) {
      x.push_back(batch.positions(s));
      v.push_back(batch.velocities(s));
      target.push_back(batch.target(s));
      energy.push_back(batch.energy(s).total());
    }
  }
  void expectSame(const BatchSimulator& batch, const std::string& what) const {
    for (int s = 0; s < batch.size(); ++s) {
      const std::size_t i = std::size_t(s);
      EXPECT_EQ(batch.positions(s), x[i]) << what << ": scene " << s;
      EXPECT_EQ(batch.velocities(s), v[i]) << what << ": scene " << s;
      EXPECT_EQ(batch.target(s), target[i]) << what << ": scene " << s;
      EXPECT_EQ(batch.energy(s).total(), energy[i]) << what << ": scene " << s;
    }
  }
  std::vector<Eigen::MatrixX3d> x, v;
  std::vector<double> target, energy;
};

// `call` is refused with an InvalidInputError whose message has `message` (which names the call,
// the scene and the field or index), and the batch is as before.
void expectRefused(const BatchSimulator& batch, const std::function<void()>& call, const std::string& message) {
  const Snapshot before(batch);
  try {
    call();
    ADD_FAILURE() << "accepted; expected \"" << message << "\"";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
  before.expectSame(batch, message);
}

// Bad input to every call: a scene out of range, an index out of the scene's range (though inside
// the batch's lists), a value Simulator refuses. Each names the call, the scene and the field or
// index, and changes nothing: afterwards every scene still follows its own Simulator, which got
// none of it.
TEST(BatchInputErrors, BadInputNamesTheSceneAndChangesNothing) {
  const std::vector<Scene> scenes = inputScenes();
  BatchAndOwn both(scenes, inputOptions(Integrator::EnergyBlend));
  BatchSimulator& b = both.batch;
  for (int step = 0; step < 3; ++step) both.step(step);
  const int n1 = scenes[1].numParticles();
  const int springs1 = int(scenes[1].springs.size());
  const std::string pins2 = std::to_string(scenes[2].pins.size());
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  Eigen::MatrixX3d bad_forces = Eigen::MatrixX3d::Zero(n1, 3);
  bad_forces(4, 1) = NAN;

  expectRefused(
      b, [&] { b.setExternalForces(3, bad_forces); }, "setExternalForces: scene 3 out of range");
  expectRefused(
      b, [&] { b.setExternalForces(1, Eigen::MatrixX3d::Zero(n1 + 1, 3)); },
      "setExternalForces: scene 1: external forces: " + std::to_string(n1 + 1) + " rows");
  expectRefused(
      b, [&] { b.setExternalForces(1, bad_forces); }, "setExternalForces: scene 1: external forces: row 4");
  expectRefused(
      b, [&] { b.setPinTarget(2, int(scenes[2].pins.size()), zero); },
      "setPinTarget: scene 2: pin " + pins2 + " out of range (the scene has " + pins2 + " pins)");
  expectRefused(
      b, [&] { b.setPinTarget(1, 0, Eigen::Vector3d(0.0, 1e151, 0.0)); }, "setPinTarget: scene 1: pin 0: target");
  expectRefused(
      b, [&] { b.pinTarget(-1, 0); }, "pinTarget: scene -1 out of range");
  expectRefused(
      b, [&] { b.pinTarget(0, 0); }, "pinTarget: scene 0: pin 0 out of range (the scene has 0 pins)");
  expectRefused(
      b, [&] { b.setColliderPosition(1, 0, zero); },
      "setColliderPosition: scene 1: collider 0 out of range (the scene has 0 colliders)");
  expectRefused(
      b, [&] { b.setColliderVelocity(1, -1, zero); }, "setColliderVelocity: scene 1: collider -1 out of range");
  expectRefused(
      b, [&] { b.colliderPosition(2, 0); }, "colliderPosition: scene 2: collider 0 out of range");
  expectRefused(
      b, [&] { b.colliderVelocity(5, 0); }, "colliderVelocity: scene 5 out of range");
  expectRefused(
      b, [&] { b.grab(1, n1, 1e3); },
      "grab: scene 1: vertex " + std::to_string(n1) + " out of range (the scene has " + std::to_string(n1) +
          " particles)");
  expectRefused(
      b, [&] { b.grab(1, 0, -1.0); }, "grab: scene 1: stiffness -1");
  expectRefused(
      b, [&] { b.grab(1, 0, INFINITY); }, "grab: scene 1: stiffness inf");
  expectRefused(
      b, [&] { b.grab(9, 0, 1e3); }, "grab: scene 9 out of range");
  expectRefused(
      b, [&] { b.release(2, -1); }, "release: scene 2: pin -1 out of range (the scene has " + pins2 + " pins)");
  expectRefused(
      b, [&] { b.release(0, 0); }, "release: scene 0: pin 0 out of range (the scene has 0 pins)");
  expectRefused(
      b, [&] { b.setElementStiffness(1, ElementKind::Spring, springs1, 1.0); },
      "setElementStiffness: scene 1: spring " + std::to_string(springs1) + " out of range (the scene has " +
          std::to_string(springs1) + ")");
  expectRefused(
      b,
      [&] {
        b.setElementStiffness(1, ElementKind::Spring, std::vector<int>{0, 1, -2}, 1.0);
      },
      "setElementStiffness: scene 1: spring -2 out of range");
  expectRefused(
      b, [&] { b.setElementStiffness(1, ElementKind::Spring, 0, -3.0); },
      "setElementStiffness: scene 1: spring stiffness -3");
  expectRefused(
      b, [&] { b.setElementStiffness(0, ElementKind::Tet, 0, 1.0); },
      "setElementStiffness: scene 0: tet 0 out of range (the scene has 0)");
  expectRefused(
      b, [&] { b.setElementStiffness(1, static_cast<ElementKind>(99), 0, 1.0); },
      "setElementStiffness: scene 1: element kind 99");
  expectRefused(
      b,
      [&] {
        b.setElementEnabled(2, ElementKind::Tet, std::vector<int>{0, 1000}, false);
      },
      "setElementEnabled: scene 2: tet 1000 out of range");
  expectRefused(
      b, [&] { b.setElementEnabled(-2, ElementKind::Tet, 0, false); }, "setElementEnabled: scene -2 out of range");
  expectRefused(
      b, [&] { b.elementEnabled(2, ElementKind::Spring, 0); },
      "elementEnabled: scene 2: spring 0 out of range (the scene has 0)");
  // A release of a released pin, after a release that was accepted.
  b.release(1, 0);
  both.alone[1].release(0);
  expectRefused(
      b, [&] { b.release(1, 0); }, "release: scene 1: pin 0 is already released");
  EXPECT_TRUE(b.elementEnabled(1, ElementKind::Spring, 0));
  for (int step = 3; step < 13; ++step) both.step(step);
}

// A scene that is inactive after a refused step takes input as an active one does, and acts on it
// once setState reactivates it: here the stiff chain of BatchSimulator.OneScenesRefusalLeaves...
// (SE explodes on its pin) is softened while refused and restarted from rest, after which it
// follows a Simulator of the softened chain started from the same state.
// setStates of several scenes (out of order, among scenes with colliders, whose contact sets
// follow) is bit for bit the same setState calls one by one: states, targets, energies and every
// later step's report, BE and the blend. Bad input to any listed scene, a scene listed twice or
// lists of different lengths are refused naming the call and the scene, and no scene changes.
TEST(BatchInputStates, SetStatesIsTheSameCallsOneByOne) {
  const std::vector<Scene> scenes = contactBatchScenes();
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend}) {
    SCOPED_TRACE(integratorName(integrator));
    const SimulatorOptions options = inputOptions(integrator);
    BatchSimulator together(scenes, options), apart(scenes, options);
    for (int step = 0; step < 4; ++step) {
      together.step();
      apart.step();
    }
    // Scenes 2 and 0 teleported 2 cm up (into and out of their colliders' margins) with new
    // velocities.
    const std::vector<int> list = {2, 0};
    std::vector<Eigen::MatrixX3d> x, v;
    for (int s : list) {
      x.push_back(together.positions(s).rowwise() + Eigen::RowVector3d(0.0, 0.02, 0.0));
      v.push_back(0.5 * together.velocities(s));
    }
    together.setStates(list, x, v);
    for (std::size_t i = 0; i < list.size(); ++i) apart.setState(list[i], x[i], v[i]);
    for (int step = 0; step <= 6; ++step) {
      for (int s = 0; s < together.size(); ++s) {
        ASSERT_EQ(together.positions(s), apart.positions(s)) << "scene " << s << ", step " << step;
        ASSERT_EQ(together.velocities(s), apart.velocities(s)) << "scene " << s << ", step " << step;
        ASSERT_EQ(together.target(s), apart.target(s)) << "scene " << s << ", step " << step;
        ASSERT_EQ(together.energy(s).total(), apart.energy(s).total()) << "scene " << s << ", step " << step;
      }
      const BatchStepReport& a = together.step();
      const BatchStepReport& b = apart.step();
      for (int s = 0; s < together.size(); ++s) {
        ASSERT_EQ(a.scenes[std::size_t(s)].event_energy, b.scenes[std::size_t(s)].event_energy) << "scene " << s;
        ASSERT_EQ(a.scenes[std::size_t(s)].branch, b.scenes[std::size_t(s)].branch) << "scene " << s;
      }
    }
    // Refusals.
    std::vector<Eigen::MatrixX3d> bad = {together.positions(1), together.positions(2)};
    bad[1](3, 2) = NAN;
    const std::vector<Eigen::MatrixX3d> v12 = {together.velocities(1), together.velocities(2)};
    expectRefused(
        together,
        [&] {
          together.setStates({1, 2}, bad, v12);
        },
        "setStates: scene 2: positions: row 3");
    expectRefused(
        together,
        [&] {
          together.setStates({1, 1}, {bad[0], bad[0]}, {v12[0], v12[0]});
        },
        "setStates: scene 1: listed twice");
    expectRefused(
        together,
        [&] {
          together.setStates({1, 3}, {bad[0], bad[0]}, {v12[0], v12[0]});
        },
        "setStates: scene 3 out of range");
    expectRefused(
        together,
        [&] {
          together.setStates({1, 2}, {bad[0]}, v12);
        },
        "setStates: 2 scenes, 1 positions");
  }
}

// Element changes book their events when something reads them or at the step, so that the
// changes of many scenes share one pass (BatchDriver::settleEvents). Changes of four scenes, one
// of them changed twice, with other input between them: the batch that books each at the step is
// bit for bit the batch that reads each event right after its change (states, targets, energies,
// the events in the step's report, every later step), and a checkpoint taken before the step
// holds the booked events (the same bytes). BE and the blend.
TEST(BatchInputEvents, ElementChangesBookedAtTheStepAreTheChangesBookedAtOnce) {
  const std::vector<Scene> scenes = mixedBatchScenes();
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend}) {
    SCOPED_TRACE(integratorName(integrator));
    const SimulatorOptions options = inputOptions(integrator);
    BatchSimulator at_once(scenes, options), at_step(scenes, options), saved(scenes, options);
    for (int step = 0; step < 3; ++step) {
      at_once.step();
      at_step.step();
      saved.step();
    }
    std::vector<double> before;
    for (int s = 0; s < at_once.size(); ++s) before.push_back(at_once.target(s));
    testing::changeElementsOfSeveralScenes(at_once, scenes, /*read_after_each=*/true);
    testing::changeElementsOfSeveralScenes(at_step, scenes, /*read_after_each=*/false);
    testing::changeElementsOfSeveralScenes(saved, scenes, /*read_after_each=*/false);
    const BatchCheckpoint checkpoint = saved.checkpoint();
    const BatchCheckpoint reference = at_once.checkpoint();
    for (int s = 0; s < at_once.size(); ++s)
      EXPECT_EQ(checkpoint.scene(s).bytes(), reference.scene(s).bytes()) << "scene " << s;
    for (int step = 0; step < 6; ++step) {
      const BatchStepReport& a = at_once.step();
      const BatchStepReport& b = at_step.step();
      for (int s = 0; s < at_once.size(); ++s) {
        const std::size_t i = std::size_t(s);
        ASSERT_EQ(a.scenes[i].event_energy, b.scenes[i].event_energy) << "scene " << s << ", step " << step;
        // Every scene's change did work (a stiffer spring, softer or fewer elements).
        if (step == 0) {
          EXPECT_NE(b.scenes[i].event_energy, 0.0) << "scene " << s;
        }
        ASSERT_EQ(at_once.positions(s), at_step.positions(s)) << "scene " << s << ", step " << step;
        ASSERT_EQ(at_once.velocities(s), at_step.velocities(s)) << "scene " << s << ", step " << step;
        ASSERT_EQ(at_once.target(s), at_step.target(s)) << "scene " << s << ", step " << step;
        ASSERT_EQ(at_once.energy(s).total(), at_step.energy(s).total()) << "scene " << s << ", step " << step;
      }
    }
    EXPECT_NE(at_step.target(0), before[0]);
  }
}

TEST(BatchInputInactive, ARefusedSceneTakesInputAndActsOnItAfterSetState) {
  ChainPendulumParams soft, stiff;
  soft.stiffness = 10.0;
  soft.pin_stiffness = 100.0;
  stiff.particles = 6;
  const std::vector<Scene> scenes = {makeChainPendulum(soft), makeChainPendulum(stiff)};
  SimulatorOptions options;
  options.integrator = Integrator::SymplecticEuler;
  options.time_step = 1e-3;
  options.energy_limit = 1.0;
  BatchSimulator batch(scenes, options);
  int step = 0;
  for (; step < 200 && batch.active(1); ++step) batch.step();
  ASSERT_FALSE(batch.active(1)) << "the stiff chain was never refused";
  const Eigen::MatrixX3d kept = batch.positions(1);
  batch.setElementStiffness(1, ElementKind::Pin, 0, soft.pin_stiffness);
  batch.setElementStiffness(1, ElementKind::Spring, std::vector<int>{0, 1, 2, 3, 4}, soft.stiffness);
  batch.setExternalForces(1, Eigen::MatrixX3d::Zero(scenes[1].numParticles(), 3));
  const int handle = batch.grab(1, 5, 50.0);
  EXPECT_EQ(handle, 1);
  batch.release(1, handle);
  batch.step();
  EXPECT_FALSE(batch.active(1));
  EXPECT_EQ(batch.positions(1), kept);

  Scene softened = scenes[1];
  softened.pins[0].stiffness = soft.pin_stiffness;
  for (Spring& spring : softened.springs) spring.stiffness = soft.stiffness;
  const Eigen::MatrixX3d x0 = scenes[1].positions, v0 = Eigen::MatrixX3d::Zero(x0.rows(), 3);
  batch.setState(1, x0, v0);
  EXPECT_TRUE(batch.active(1));
  Simulator own(softened, options);
  own.setExternalForces(Eigen::MatrixX3d::Zero(x0.rows(), 3));
  own.grab(5, 50.0);
  own.release(1);
  for (int i = 0; i < 100; ++i) {
    const BatchStepReport& report = batch.step();
    own.step();
    ASSERT_TRUE(report.refusals[1].empty()) << "step " << i << ": " << report.refusals[1];
    testing::expectSameState(batch.positions(1), batch.velocities(1), own, "step " + std::to_string(i));
  }
}

}  // namespace
}  // namespace stabint
