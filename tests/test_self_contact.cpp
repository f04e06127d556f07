// Self-contact (docs/method.md, "Self-contact"): continuous detection of vertex-triangle and
// edge-edge pairs over a step, the impulses that keep surfaces apart, and whole runs whose
// surfaces never intersect, checked by an exact triangle-triangle test.
#include <stabint/stabint.hpp>

#include "backend_suite.hpp"
#include "contact_scenes.hpp"
#include "contact/self_contact.hpp"
#include "contact/surface_crossings.hpp"
#include "triangle_intersections.hpp"
#include "energy_band.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace stabint {
namespace {

using Rows = Eigen::Ref<const Eigen::MatrixX3d, 0, Eigen::OuterStride<>>;

// A scene of loose particles with the given surface triangles (no elements: the guard alone).
Scene loose(const Eigen::MatrixX3d& x, const std::vector<std::array<int, 3>>& triangles) {
  Scene s;
  s.positions = s.rest_positions = x;
  s.velocities = Eigen::MatrixX3d::Zero(x.rows(), 3);
  s.masses = Eigen::VectorXd::Constant(x.rows(), 0.1);
  s.triangles = triangles;
  return s;
}

Eigen::Vector3d momentum(const Eigen::MatrixX3d& v, const Eigen::VectorXd& m) {
  return (v.array().colwise() * m.array()).colwise().sum().transpose();
}

// A triangle in the plane y = 0 (vertices 1-3) and, 0.1 above it, a small triangle (0, 4, 5:
// surface particles are the vertices of its triangles) lying flat over its middle.
struct VertexOverTriangle {
  Eigen::MatrixX3d x0{6, 3};
  std::vector<std::array<int, 3>> triangles{{1, 2, 3}, {0, 4, 5}};
  VertexOverTriangle() {
    x0 << 0.2, 0.1, 0.2,            //
        0, 0, 0, 0, 0, 1, 1, 0, 0,  // y = 0
        0.25, 0.1, 0.2, 0.2, 0.1, 0.25;
  }
  // The small triangle moved by dy (a translation: its vertices cross together).
  Eigen::MatrixX3d moved(double dy) const {
    Eigen::MatrixX3d x = x0;
    for (int i : {0, 4, 5}) x(i, 1) += dy;
    return x;
  }
};

// Signed distance of x's vertex i above the plane of the big triangle (1, 2, 3).
double aboveBigTriangle(const Eigen::MatrixX3d& x, int i) {
  const Eigen::Vector3d a = x.row(1), b = x.row(2), c = x.row(3), p = x.row(i);
  Eigen::Vector3d n = (b - a).cross(c - a).normalized();
  if (n.y() < 0.0) n = -n;
  return n.dot(p - a);
}

constexpr double kThickness = 0.01;

TEST(SelfContact, ATriangleThrownThroughAnotherWithinTheStepIsStoppedOnItsSide) {
  VertexOverTriangle f;
  Scene scene = loose(f.x0, f.triangles);
  scene.masses.segment(1, 3).setConstant(10.0);  // a heavy big triangle: it barely tilts
  const SelfContact guard(scene, kThickness);
  // Within one step the small triangle goes from 0.1 above the big one to 0.3 below it: both
  // ends are far from it, only the path crosses.
  Eigen::MatrixX3d x1 = f.moved(-0.4), v1 = Eigen::MatrixX3d::Zero(6, 3);
  for (int i : {0, 4, 5}) v1(i, 1) = -12.0;
  const std::vector<ContactEvent> events = guard.events(Rows(f.x0), x1, kThickness);
  ASSERT_EQ(events.size(), 3u);  // each small vertex against the big triangle
  for (const ContactEvent& e : events) {
    EXPECT_TRUE(e.crossing);
    EXPECT_NEAR(e.normal.y(), 1.0, 1e-12);
  }

  const Eigen::Vector3d p_before = momentum(v1, scene.masses);
  const Eigen::Vector3d c_before = momentum(x1, scene.masses);
  const double k_before =
      0.5 * (v1.rowwise().squaredNorm().transpose().array() * scene.masses.transpose().array()).sum();
  const SelfContactResult r = guard.resolve(Rows(f.x0), x1, v1, scene.masses, {});
  EXPECT_TRUE(r.positions_moved);
  EXPECT_TRUE(r.velocities_changed);
  EXPECT_EQ(r.frozen, 0);
  // Every small vertex on its side of the big triangle at about the thickness (the big triangle
  // tilts a little under the three impulses, one after the other).
  for (int i : {0, 4, 5}) {
    EXPECT_GE(aboveBigTriangle(x1, i), 0.5 * kThickness) << "vertex " << i;
    EXPECT_LT(aboveBigTriangle(x1, i), 2.0 * kThickness) << "vertex " << i;
  }
  EXPECT_EQ(testing::intersectingTrianglePairs(x1, f.triangles), 0);
  // Inelastic and momentum-conserving: the centre of mass and the momentum stay (to
  // round-off), the small triangle no longer approaches the big one, and the kinetic energy
  // lost is what the result books.
  EXPECT_NEAR((momentum(v1, scene.masses) - p_before).norm(), 0.0, 1e-12);
  EXPECT_NEAR((momentum(x1, scene.masses) - c_before).norm(), 0.0, 1e-12);
  for (int i : {0, 4, 5}) EXPECT_GE(v1(i, 1) - v1(1, 1), -1e-9) << "vertex " << i;
  const double k_after =
      0.5 * (v1.rowwise().squaredNorm().transpose().array() * scene.masses.transpose().array()).sum();
  EXPECT_NEAR(r.kinetic_removed, k_before - k_after, 1e-12);
  EXPECT_GT(r.kinetic_removed, 0.0);
  for (const ContactEvent& e : guard.events(Rows(f.x0), x1, 0.0)) EXPECT_FALSE(e.crossing);
}

TEST(SelfContact, APinnedTriangleLeavesTheWholeCorrectionToTheOtherOne) {
  VertexOverTriangle f;
  const Scene scene = loose(f.x0, f.triangles);
  const SelfContact guard(scene, kThickness);
  Eigen::MatrixX3d x1 = f.moved(-0.4), v1 = Eigen::MatrixX3d::Zero(6, 3);
  guard.resolve(Rows(f.x0), x1, v1, scene.masses, {1, 2, 3});
  for (int i = 1; i <= 3; ++i) EXPECT_EQ(x1.row(i), f.x0.row(i)) << "vertex " << i;
  for (int i : {0, 4, 5}) EXPECT_NEAR(x1(i, 1), kThickness, 1e-15) << "vertex " << i;
}

TEST(SelfContact, APathBesideTheTriangleIsNoEvent) {
  VertexOverTriangle f;
  const Scene scene = loose(f.x0, f.triangles);
  const SelfContact guard(scene, kThickness);
  Eigen::MatrixX3d x0 = f.x0;
  for (int i : {0, 4, 5}) x0(i, 2) -= 0.3;  // over z < 0: beside the big triangle's edge z = 0
  Eigen::MatrixX3d x1 = x0;
  for (int i : {0, 4, 5}) x1(i, 1) -= 0.4;
  EXPECT_TRUE(SelfContact(loose(x0, f.triangles), kThickness).events(Rows(x0), x1, kThickness).empty());
}

TEST(SelfContact, APathThatGrazesTheTriangleWithoutCrossingIsCaught) {
  // The triangle turns about its edge on the z axis (its third vertex from y = 0.1 to -0.1)
  // while the particle slides along x under it from x = 0.9 to 0.1. The plane's height over the
  // particle, (0.9 - 0.8 t)(0.1 - 0.2 t), is least at t = 0.8125 (-0.015625, over x = 0.25):
  // a particle just below that never crosses the plane, it only grazes it there, so the
  // coplanarity has no sign change and only the check at its extremum finds the pair.
  auto run = [](double below) {
    // The particle is the top of a triangle (0, 4, 5) hanging 0.5 below it in the plane z = 0.25.
    Eigen::MatrixX3d x0(6, 3);
    x0 << 0.9, -0.015625 - below, 0.25, 0, 0, 0, 0, 0, 1, 1, 0.1, 0,  //
        0.9, -0.515625 - below, 0.25, 0.95, -0.515625 - below, 0.25;
    Eigen::MatrixX3d x1 = x0;
    for (int i : {0, 4, 5}) x1(i, 0) -= 0.8;
    x1(3, 1) = -0.1;
    const Scene scene = loose(x0, {{1, 2, 3}, {0, 4, 5}});
    int crossings = 0;
    for (const ContactEvent& e : SelfContact(scene, kThickness).events(Rows(x0), x1, 0.0))
      crossings += e.crossing && e.vertices == std::array<int, 4>{0, 1, 2, 3} ? 1 : 0;
    return crossings;
  };
  EXPECT_EQ(run(0.05 * kThickness), 1);
  EXPECT_EQ(run(0.5 * kThickness), 0);  // half a thickness below: no touch
}

TEST(SelfContact, EdgesCrossingEachOtherAreStopped) {
  // Two triangles whose edges only cross: the upper one's edge (0, 1) along x falls through
  // the lower one's edge (3, 4) along z; no vertex passes through a triangle.
  Eigen::MatrixX3d x0(6, 3);
  x0 << -1, 0.05, 0.5, 1, 0.05, 0.5, 0, 0.5, 0.5,  // upper: edge 0-1 at y = 0.05, apex above
      0.5, 0, -1, 0.5, 0, 1, 0.5, -0.5, 0;         // lower: edge 3-4 at y = 0, apex below
  const Scene scene = loose(x0, {{0, 1, 2}, {3, 4, 5}});
  const SelfContact guard(scene, kThickness);
  Eigen::MatrixX3d x1 = x0, v1 = Eigen::MatrixX3d::Zero(6, 3);
  x1.col(1).head(3).array() -= 0.2;  // the upper triangle drops 0.2: its edge ends 0.15 below
  v1.col(1).head(3).array() = -6.0;
  const std::vector<ContactEvent> events = guard.events(Rows(x0), x1, kThickness);
  ASSERT_FALSE(events.empty());
  bool edge_edge = false;
  for (const ContactEvent& e : events) edge_edge = edge_edge || (e.vertices[0] == 0 && e.vertices[1] == 1);
  EXPECT_TRUE(edge_edge);
  const SelfContactResult r = guard.resolve(Rows(x0), x1, v1, scene.masses, {});
  EXPECT_EQ(r.frozen, 0);
  EXPECT_EQ(testing::intersectingTrianglePairs(x1, scene.triangles), 0);
  // Where they crossed (3/4 along each edge), the upper edge rests on the lower one at the
  // thickness.
  const double upper = 0.25 * x1(0, 1) + 0.75 * x1(1, 1), lower = 0.25 * x1(3, 1) + 0.75 * x1(4, 1);
  EXPECT_GE(upper - lower, kThickness - 1e-12);
  EXPECT_LT(upper - lower, kThickness + 1e-3);
  EXPECT_TRUE(guard.events(Rows(x0), x1, 0.5 * kThickness).empty());
}

TEST(SelfContact, AVeryFastTriangleIsCaughtAndOneThatStopsShortIsNot) {
  VertexOverTriangle f;
  const Scene scene = loose(f.x0, f.triangles);
  const SelfContact guard(scene, kThickness);
  EXPECT_EQ(guard.events(Rows(f.x0), f.moved(-1e4), kThickness).size(), 3u);  // 300 km/s at h = 1/30
  EXPECT_TRUE(guard.events(Rows(f.x0), f.moved(-0.05), kThickness).empty());  // stops 5 thicknesses above
}

}  // namespace
}  // namespace stabint

namespace stabint {
namespace {

using testing::clothOnCloth;
using testing::crumplingCloth;

// The most triangle pairs that intersect at any of `steps` steps of `scene`.
int worstIntersections(const Scene& scene, SimulatorOptions options, int steps) {
  Simulator sim(scene, options);
  int worst = 0;
  for (int k = 0; k < steps; ++k) {
    sim.step();
    worst = std::max(worst, testing::intersectingTrianglePairs(sim.positions(), scene.triangles));
  }
  return worst;
}

TEST(SelfContactRun, ACrumplingClothNeverIntersectsItself) {
  SimulatorOptions o;
  o.integrator = Integrator::BackwardEuler;
  // The scene's own test: without self-contact it intersects.
  EXPECT_GT(worstIntersections(crumplingCloth(), o, 60), 100);
  o.self_contact_thickness = 4e-3;
  EXPECT_EQ(worstIntersections(crumplingCloth(), o, 120), 0);
}

// Converged backward Euler loses energy at every step, so what self-contact's pushes add after the
// solve must be relaxed out (BatchDriver::relaxSelfContactPushes), not left above H*. On the
// crumpling cloth at 200 iterations a first round takes out 40 % of a 1.6 J gain, which left 1.8
// H_0 above H* when a round had to take out half. The rounds go on while H is above its band; one
// step ends 0.11 H_0 above, where a round that raised H is undone, so the bound is 0.25 H_0.
TEST(SelfContactRun, ConvergedBackwardEulerRelaxesWhatThePushesAdd) {
  SimulatorOptions o;
  o.backend = BackendKind::CpuReference;
  o.integrator = Integrator::BackwardEuler;
  o.iterations = 200;
  o.self_contact_thickness = 4e-3;
  Simulator sim(crumplingCloth(), o);
  const double h0 = sim.energy().total();
  double worst = -1.0;
  for (int k = 0; k < 30; ++k) {
    const StepReport& r = sim.step();
    worst = std::max(worst, r.energy.total() - r.target);
  }
  EXPECT_LT(worst, 0.25 * h0);
}

// The library's crossing test (double precision) finds the pairs CGAL's exact test finds, on a
// crumpled cloth that passed through itself (no self-contact: hundreds of pairs) and on every step
// of the way there (a frame with none included). Two triangles in general position are decided
// the same way unless a point lies within round-off of the other's plane or edge; the crumpled
// cloth has none so near. A flat sheet turned by rounded sines (the upper cloth of clothOnCloth)
// is in one plane up to round-off, where a test of signs alone found crossings.
TEST(SelfContact, TheCrossingTestFindsTheExactTestsPairs) {
  const Scene sheets = clothOnCloth();
  EXPECT_TRUE(crossingTriangles(sheets.positions, sheets.triangles).empty());
  const Scene scene = crumplingCloth();
  SimulatorOptions o;
  o.integrator = Integrator::BackwardEuler;
  Simulator sim(scene, o);
  EXPECT_TRUE(crossingTriangles(sim.positions(), scene.triangles).empty());
  std::size_t most = 0;
  for (int k = 0; k < 60; ++k) {
    sim.step();
    const std::vector<std::pair<int, int>> exact =
        testing::intersectingTrianglePairList(sim.positions(), scene.triangles);
    ASSERT_EQ(crossingTriangles(sim.positions(), scene.triangles), exact) << "step " << k;
    most = std::max(most, exact.size());
  }
  EXPECT_GT(most, 100u);
}

// A start that crosses itself is refused with a message naming two triangles that cross, and so
// is a new state that does (nothing changed then); without self-contact the same scene runs.
TEST(SelfContactRun, AStartThatCrossesItselfIsRefused) {
  Scene lower = testing::horizontalCloth(10, 0.1);
  Scene upper = lower;
  // A copy turned 90 degrees about the x axis through the first one's plane: they cross along a line.
  for (int i = 0; i < upper.numParticles(); ++i) {
    const double y = upper.positions(i, 1), z = upper.positions(i, 2);
    upper.positions.row(i) << upper.positions(i, 0), 0.1 + z, y - 0.1 + 0.013;
  }
  upper.rest_positions = upper.positions;
  const Scene crossing = testing::combined(lower, upper);
  SimulatorOptions o;
  o.self_contact_thickness = 2e-3;
  try {
    Simulator refused(crossing, o);
    FAIL() << "a crossing start was accepted";
  } catch (const InvalidInputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("self-contact: surface triangle"), std::string::npos) << what;
    EXPECT_NE(what.find("cross ("), std::string::npos) << what;
  }
  SimulatorOptions off;
  EXPECT_NO_THROW(Simulator(crossing, off).step());
  // In a batch the message names the scene that crosses.
  try {
    BatchSimulator refused({lower, crossing}, o);
    FAIL() << "a batch with a crossing scene was accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("scene 1: self-contact: surface triangle", 0), 0u) << e.what();
  }

  Scene apart = testing::combined(lower, testing::horizontalCloth(10, 0.3));
  Simulator sim(apart, o);
  sim.step();
  const Eigen::MatrixX3d x = sim.positions(), v = sim.velocities();
  const double t = sim.time();
  EXPECT_THROW(sim.setState(crossing.positions, Eigen::MatrixX3d::Zero(x.rows(), 3)), InvalidInputError);
  EXPECT_EQ(sim.positions(), x);
  EXPECT_EQ(sim.velocities(), v);
  EXPECT_EQ(sim.time(), t);
}

class SelfContactOnEveryBackend : public testing::BackendTest {
 protected:
  // A landing of `scene` with options `o` on this backend: a checkpoint taken at step 12 continues
  // bit for bit, and the backend follows the CPU reference for 20 steps in double (to 1e-9 m) and
  // `float_steps` in float (to `float_tolerance`).
  void followsTheCpuReferenceAndContinuesFromACheckpoint(const Scene& scene, const SimulatorOptions& o, int float_steps,
                                                         double float_tolerance);
};

TEST_P(SelfContactOnEveryBackend, AClothDroppedOnAnotherRestsOnIt) {
  const Scene scene = clothOnCloth();
  SimulatorOptions plain = options();
  EXPECT_GT(worstIntersections(scene, plain, 40), 0);

  SimulatorOptions o = options();
  o.self_contact_thickness = 3e-3;
  Simulator sim(scene, o);
  double booked = 0.0, excess = 0.0, kinetic = 0.0;
  for (int k = 0; k < 40; ++k) {
    const StepReport& r = sim.step();
    ASSERT_EQ(testing::intersectingTrianglePairs(sim.positions(), scene.triangles), 0) << "step " << k;
    booked += r.contact_projection;
    excess = std::max(excess, r.energy.total() - r.target);
    kinetic = std::max(kinetic, r.energy.kinetic);
  }
  EXPECT_LT(booked, 0.0);  // the landing's impulses took energy, and H* lost it
  // The books at the impact, by the contact issue's measure: the blend's H at most 0.05 of the
  // run's largest kinetic energy above H* (0.0008 measured; 11 with the impulses after the solve
  // alone, which stretched the springs at the contact's edge).
  EXPECT_LE(excess, 0.05 * kinetic);
  // The upper cloth rests on the lower one: on average at least half the thickness above it (its
  // corners, which overhang the lower cloth, may reach the ground).
  const int n = scene.numParticles() / 2;
  const Eigen::MatrixX3d x = sim.positions();
  EXPECT_GT(x.col(1).tail(n).mean(), x.col(1).head(n).mean() + 0.5 * o.self_contact_thickness);
}

TEST_P(SelfContactOnEveryBackend, FollowsTheCpuReferenceAndContinuesFromACheckpointBitForBit) {
  for (int supports : {0, 2}) {
    SCOPED_TRACE(supports ? "with supports" : "without supports");
    SimulatorOptions o = options();
    o.self_contact_thickness = 3e-3;
    o.self_contact_supports = supports;
    // Double over the landing (its first impulses at step 4): 7e-13 m measured. Float up to the
    // landing, 1e-5 m measured over 4 steps: from then on a pair within a rounding of the
    // impulses' thresholds takes its impulse on one backend and not the other, and the landings
    // part by millimetres, as two CPU runs started float's difference apart do
    // (AClothOnABodyFollowsTheCpuReferenceAndContinuesFromACheckpoint). The property tests check the landing's float
    // path on every backend.
    followsTheCpuReferenceAndContinuesFromACheckpoint(clothOnCloth(), o, 4, 1e-4);
  }
}

void SelfContactOnEveryBackend::followsTheCpuReferenceAndContinuesFromACheckpoint(const Scene& scene,
                                                                                  const SimulatorOptions& o,
                                                                                  int float_steps,
                                                                                  double float_tolerance) {
  Simulator sim(scene, o);
  for (int k = 0; k < 12; ++k) sim.step();
  const Checkpoint at12 = sim.checkpoint();
  for (int k = 0; k < 8; ++k) sim.step();
  const Eigen::MatrixX3d x20 = sim.positions(), v20 = sim.velocities();
  sim.restore(at12);
  for (int k = 0; k < 8; ++k) sim.step();
  EXPECT_EQ(sim.positions(), x20);
  EXPECT_EQ(sim.velocities(), v20);
  SimulatorOptions cpu = o;
  cpu.backend = BackendKind::CpuReference;
  Simulator here(scene, o), reference(scene, cpu);
  const int steps = backend().isFloat() ? float_steps : 20;
  for (int k = 0; k < steps; ++k) {
    here.step();
    reference.step();
  }
  const double difference = (here.positions() - reference.positions()).cwiseAbs().maxCoeff();
  std::printf("%d steps: %.3g m from the CPU reference\n", steps, difference);
  EXPECT_LT(difference, backend().isFloat() ? float_tolerance : 1e-9);
}

// The default supports (on a heavy body, SimulatorOptions::self_contact_supports 1): a cloth
// landing on a tet bar (its first contact at step 5) against the CPU reference: double to
// round-off amplified over 20 steps (8e-11 m measured), float over the 5 steps before the contact
// to 0.2 mm (3.2e-5 m measured, float's rounding of the falling cloth amplified by the solves).
// Float stops at the landing, which is chaotic: CPU runs started 2e-5 m apart (random per
// coordinate, float's difference by then) part by 0.14-3.2 mm at step 5 and 5-21 mm at step 7
// over four starts, and float parts from double by 3.2 and 22 mm there, the same.
TEST_P(SelfContactOnEveryBackend, AClothOnABodyFollowsTheCpuReferenceAndContinuesFromACheckpoint) {
  SimulatorOptions o = options();
  o.self_contact_thickness = 5e-3;
  followsTheCpuReferenceAndContinuesFromACheckpoint(testing::clothOnBar(), o, 5, 2e-4);
}

// Pushes after the solve that relax through the elements (BatchDriver::relaxSelfContactPushes):
// a 30 kg cloth thrown at 4 and 8 m/s onto a 1e5 Pa bar, whose pushes relax within the first
// steps (a relaxing step with a partner takes 23 iterations: the candidate's 10, the partner's 3
// and the relaxation's 10; which steps relax depends on the landing, so the test asks for one over
// both throws). On this backend, for each throw, a checkpoint taken before the landing continues
// bit for bit, H stays within 1.5 bands of H* with no crossing at each of 20 steps, and the run
// follows the CPU reference: in double over the 20 steps to 1e-9 m (5e-11 measured), in float
// over the first 2 steps to 0.2 mm (6.5e-5 m measured at 4 m/s: float's rounding amplified by
// implicit midpoint's solve, and the first approach stops, which both take alike). The landing
// parts float and double from then on (1 cm at 4 m/s by step 4), as
// AClothOnABodyFollowsTheCpuReferenceAndContinuesFromACheckpoint shows for a landing, so float's
// relaxations are checked by the band and the crossings.
TEST_P(SelfContactOnEveryBackend, AHeavyClothsPushesRelaxThroughTheElements) {
  const int cloth = 900;
  int most_iterations = 0;
  for (const double speed : {4.0, 8.0}) {
    SCOPED_TRACE(speed);
    TetBarParams bar;
    bar.stiffness = 1e5;
    Scene scene = testing::clothOnBar(bar);
    scene.velocities.bottomRows(cloth).col(1).setConstant(-speed);
    scene.masses.tail(cloth) *= 30.0;
    const std::vector<std::array<int, 3>> surface = ContactSurface::of(scene).triangles;
    SimulatorOptions o = options();
    o.self_contact_thickness = 4e-3;
    SimulatorOptions cpu = o;
    cpu.backend = BackendKind::CpuReference;
    Simulator here(scene, o), reference(scene, cpu);
    const int compared = backend().isFloat() ? 2 : 20;
    Checkpoint at2;
    Eigen::MatrixX3d x6, v6;
    for (int k = 0; k < 20; ++k) {
      if (k == 2) at2 = here.checkpoint();
      const StepReport& r = here.step();
      const double tau = testing::energyBand(here, r);
      EXPECT_LE(r.energy.total() - r.target, 1.5 * tau) << "step " << k;
      EXPECT_EQ(testing::intersectingTrianglePairs(here.positions(), surface), 0) << "step " << k;
      if (k == 5) x6 = here.positions(), v6 = here.velocities();
      most_iterations = std::max(most_iterations, r.iterations);
      if (k < compared) reference.step();
      if (k + 1 == compared) {
        const double difference = (here.positions() - reference.positions()).cwiseAbs().maxCoeff();
        std::printf("%g m/s, %d steps: %.3g m from the CPU reference\n", speed, compared, difference);
        EXPECT_LT(difference, backend().isFloat() ? 2e-4 : 1e-9);
      }
    }
    here.restore(at2);
    for (int k = 2; k < 6; ++k) here.step();
    EXPECT_EQ(here.positions(), x6);
    EXPECT_EQ(here.velocities(), v6);
  }
  // A relaxation ran: a step without one takes at most the candidate's and the partner's budgets.
  EXPECT_GT(most_iterations, 2 * SimulatorOptions{}.iterations);
}

STABINT_ON_EVERY_BACKEND(SelfContactOnEveryBackend);

}  // namespace
}  // namespace stabint

namespace stabint {
namespace {

// A batch of `first` and `second` stepped `steps` times beside each scene's own Simulator: each
// scene follows its Simulator to the batch tests' standard (tests/batch_scenes.hpp: states to 1e-9
// of the scene's size; the batch's factor orders and updates its blocks otherwise), and so does
// its booked loss after the solve, the potentials' change over the pushes, which follows the
// states' round-off more closely than the energy: 1e-11 of E_scale (4e-12 measured). Returns each
// scene's booked loss and the batch's positions of the first scene at the end.
struct BatchAndSimulators {
  double booked[2] = {0.0, 0.0};
  Eigen::MatrixX3d first_positions;
};
BatchAndSimulators stepBatchAndSimulators(const Scene& first, const Scene& second, const SimulatorOptions& o,
                                          int steps) {
  BatchSimulator batch({first, second}, o);
  Simulator alone[2] = {Simulator(first, o), Simulator(second, o)};
  BatchAndSimulators run;
  for (int k = 0; k < steps; ++k) {
    const BatchStepReport& r = batch.step();
    for (int s = 0; s < 2; ++s) {
      const StepReport& own = alone[s].step();
      EXPECT_NEAR(r.scenes[std::size_t(s)].contact_projection, own.contact_projection, 1e-11 * alone[s].energyScale())
          << "scene " << s << ", step " << k;
      EXPECT_LE((batch.positions(s) - alone[s].positions()).cwiseAbs().maxCoeff(), 1e-9)
          << "scene " << s << ", step " << k;
      run.booked[s] += own.contact_projection;
    }
  }
  run.first_positions = batch.positions(0);
  return run;
}

TEST(SelfContactRun, EachSceneOfABatchHasItsOwnSelfContactAsItsSimulator) {
  // Two scenes of one batch: the cloths landing on each other, and the same cloths moved 2 m
  // aside and 1 cm lower (another landing). Each follows its own Simulator to the batch tests'
  // standard (tests/batch_scenes.hpp: states to 1e-9 of the scene's size, the energy booked to
  // 1e-12 of E_scale, 1e-11 for the booked contact loss; the batch's factor orders and updates
  // its blocks otherwise): its surface,
  // its impulses and its books are its own.
  SimulatorOptions o;
  o.self_contact_thickness = 3e-3;
  const Scene first = clothOnCloth();
  Scene second = first;
  second.positions.col(0).array() += 2.0;
  second.positions.col(1).array() -= 0.01;
  second.rest_positions = second.positions;
  second.colliders.front().center.x() = 2.0;
  const BatchAndSimulators run = stepBatchAndSimulators(first, second, o, 12);
  // Both landings took their impulses within the 12 steps.
  EXPECT_LT(run.booked[0], 0.0);
  EXPECT_LT(run.booked[1], 0.0);
}

// A batch whose scenes relax their pushes at different steps (BatchDriver::relaxSelfContactPushes
// solves only the scenes that need it): a 30 kg cloth thrown at 4 and at 8 m/s onto a 1e5 Pa bar.
// Each follows its own Simulator to the batch tests' standard (3.5e-12 m measured over 12 steps;
// the 4 m/s scene relaxes at steps 3 to 6, the 8 m/s one at step 3 with no partner).
TEST(SelfContactRun, EachSceneOfABatchRelaxesItsPushesAsItsSimulator) {
  SimulatorOptions o;
  o.self_contact_thickness = 4e-3;
  const auto drop = [](double speed) {
    TetBarParams bar;
    bar.stiffness = 1e5;
    Scene scene = testing::clothOnBar(bar);
    scene.velocities.bottomRows(900).col(1).setConstant(-speed);
    scene.masses.tail(900) *= 30.0;
    return scene;
  };
  const Scene slow = drop(4.0);
  stepBatchAndSimulators(slow, drop(8.0), o, 12);
  Simulator alone(slow, o);
  int most_iterations = 0;
  for (int k = 0; k < 12; ++k) most_iterations = std::max(most_iterations, alone.step().iterations);
  EXPECT_GT(most_iterations, 2 * o.iterations);  // it relaxed: more than the candidate's and partner's
}

// A batch whose scenes differ in their supports (SimulatorOptions::self_contact_supports 1): the
// cloth on a tet bar gets a support collider, the two cloths none. Each scene follows its own
// Simulator to the standard above through both landings, and the bar scene's supports hold (its
// cloth stays above the bar).
TEST(SelfContactRun, ABatchGivesSupportsToTheScenesWithABodyAsTheirSimulators) {
  SimulatorOptions o;
  o.self_contact_thickness = 5e-3;
  const Eigen::MatrixX3d x = stepBatchAndSimulators(testing::clothOnBar(), clothOnCloth(), o, 16).first_positions;
  const int cloth = 900;
  EXPECT_GT(x.col(1).tail(cloth).maxCoeff(), x.col(1).head(x.rows() - cloth).maxCoeff());
}

// BDF2 with self-contact (docs/method.md, "Self-contact", the BDF2 rule): a step that
// self-contact corrects restarts BDF2 with a BE step, as a jump does, since the corrections are
// not a BDF2 step and its history contradicts them. The cloths landing on each other peak at
// H = 0.71 J (from 0.096 J); continuing from the history instead they peaked at 23.8 J. BDF2
// without self-contact peaks at 1.87 J on this scene (its own ground contact), the bound's
// margin. A batch of several scenes would restart them all: refused, naming the option.
TEST(SelfContactRun, BDF2RestartsWhereSelfContactCorrects) {
  SimulatorOptions o;
  o.integrator = Integrator::BDF2;
  o.self_contact_thickness = 4e-3;
  Simulator sim(clothOnCloth(), o);
  double highest = sim.energy().total();
  for (int k = 0; k < 150; ++k) {
    sim.step();
    highest = std::max(highest, sim.energy().total());
  }
  EXPECT_LT(highest, 2.5);
  try {
    BatchSimulator batch({clothOnCloth(), clothOnCloth()}, o);
    FAIL() << "a BDF2 batch of two scenes with self-contact was accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("self_contact_thickness"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("BDF2"), std::string::npos) << e.what();
  }
}

// A tet body answers an impulse as a rigid body (docs/method.md, "Self-contact"): two single
// tets, the upper one thrown through the lower one within a step. After the guard nothing
// crosses, the momentum is kept, and each tet's change of velocity is a rigid motion (no edge
// stretches at a rate) and its positions keep their edge lengths (to the push's linearized
// rotation, 1e-6 of the edge).
TEST(SelfContact, ATetBodyAnswersAsARigidBody) {
  Scene scene;
  scene.positions.resize(8, 3);
  scene.positions << 0, 0, 0, 1, 0, 0, 0, 0, 1, 0.3, 0.5, 0.3,  // the lower tet, apex up
      0.2, 0.7, 0.2, 0.9, 0.6, 0.1, 0.3, 0.65, 0.8, 0.4, 1.2, 0.4;
  scene.rest_positions = scene.positions;
  scene.velocities = Eigen::MatrixX3d::Zero(8, 3);
  scene.masses = Eigen::VectorXd::Constant(8, 0.5);
  scene.masses.tail(4).setConstant(0.2);
  for (int b : {0, 4}) {
    Tet t;
    t.vertices = {b, b + 1, b + 3, b + 2};
    Eigen::Matrix3d d;
    for (int k = 0; k < 3; ++k)
      d.col(k) = (scene.positions.row(t.vertices[std::size_t(k + 1)]) - scene.positions.row(b)).transpose();
    if (d.determinant() < 0.0) std::swap(t.vertices[2], t.vertices[3]);
    t.stiffness = 1e5;
    scene.tets.push_back(t);
  }
  const SelfContact guard(scene, kThickness);
  ASSERT_EQ(guard.surface().triangles.size(), 8u);  // the tets' faces
  const Eigen::MatrixX3d x0 = scene.positions;
  Eigen::MatrixX3d x1 = x0, v1 = Eigen::MatrixX3d::Zero(8, 3);
  for (int i = 4; i < 8; ++i) {
    v1(i, 1) = -15.0;
    x1(i, 1) -= 0.5;  // its lowest corner ends 0.4 inside the lower tet's apex region
  }
  const Eigen::MatrixX3d v_before = v1;
  ASSERT_GT(testing::intersectingTrianglePairs(x1, guard.surface().triangles), 0);
  const SelfContactResult r = guard.resolve(Rows(x0), x1, v1, scene.masses, {});
  EXPECT_GT(r.events, 0);
  EXPECT_EQ(testing::intersectingTrianglePairs(x1, guard.surface().triangles), 0);
  EXPECT_NEAR((momentum(v1, scene.masses) - momentum(v_before, scene.masses)).norm(), 0.0, 1e-12);
  EXPECT_GT(r.kinetic_removed, 0.0);
  for (int b : {0, 4}) {
    for (int i = b; i < b + 4; ++i) {
      for (int j = i + 1; j < b + 4; ++j) {
        const Eigen::Vector3d edge0 = (x0.row(i) - x0.row(j)).transpose();
        const Eigen::Vector3d dv = (v1.row(i) - v_before.row(i) - v1.row(j) + v_before.row(j)).transpose();
        const Eigen::Vector3d edge1 = (x1.row(i) - x1.row(j)).transpose();
        const Eigen::Vector3d moved = ((x1.row(i) - x0.row(i)) - (x1.row(j) - x0.row(j))).transpose();
        // The pushes are rigid about the solve's positions x1, here x0 moved as a whole.
        EXPECT_NEAR(dv.dot(edge0), 0.0, 1e-9 * (1.0 + dv.norm())) << "edge " << i << "-" << j;
        EXPECT_NEAR(edge1.norm(), (x0.row(i) - x0.row(j)).norm(), 1e-6 + moved.squaredNorm()) << i << "-" << j;
      }
    }
  }
}

// Inverted tets of `scene`'s at x.
int invertedTets(const Scene& scene, const Eigen::MatrixX3d& x) {
  int count = 0;
  for (const Tet& t : scene.tets) {
    Eigen::Matrix3d d;
    for (int k = 0; k < 3; ++k) d.col(k) = (x.row(t.vertices[std::size_t(k + 1)]) - x.row(t.vertices[0])).transpose();
    if (!(d.determinant() > 0.0)) ++count;
  }
  return count;
}

// Two soft bodies dropped onto each other (the target): two tet bars of one scene, one on
// the ground, the other crossing it and falling onto it, at rest and thrown at 10 m/s, of the
// default 1e5 Pa and of 1e6 Pa, with backward Euler and the blend. Without self-contact the upper
// bar sinks through the lower one. With it, over 90 steps (3 s: the landing, the upper bar
// tipping over the lower one onto the ground): no surface triangle pair intersects and no tet
// inverts at any step, and the blend keeps its books (H at most 0.05 of the run's largest
// kinetic energy above H*; 0.023 measured, on the 1e6 Pa bar set down at rest).
TEST(SelfContactRun, TwoTetBarsDroppedOnEachOtherNeitherInterpenetrateNorInvert) {
  const std::vector<std::array<int, 3>> surface = ContactSurface::of(testing::barOnBar()).triangles;
  {
    SimulatorOptions plain;
    plain.integrator = Integrator::BackwardEuler;
    Simulator sim(testing::barOnBar(), plain);
    int worst = 0;
    for (int k = 0; k < 40; ++k) {
      sim.step();
      worst = std::max(worst, testing::intersectingTrianglePairs(sim.positions(), surface));
    }
    EXPECT_GT(worst, 10);
  }
  for (double stiffness : {1e5, 1e6}) {
    for (double speed : {0.0, 10.0}) {
      for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend}) {
        Scene scene = testing::barOnBar();
        for (Tet& t : scene.tets) t.stiffness = stiffness;
        const int n = scene.numParticles() / 2;
        scene.velocities.bottomRows(n).col(1).setConstant(-speed);
        SimulatorOptions o;
        o.integrator = integrator;
        o.self_contact_thickness = 5e-3;
        Simulator sim(scene, o);
        char name[64];
        std::snprintf(name, sizeof name, "%g Pa at %g m/s, %s", stiffness, speed,
                      integrator == Integrator::BackwardEuler ? "BE" : "the blend");
        double excess = 0.0, kinetic = 0.0;
        for (int k = 0; k < 90; ++k) {
          const StepReport& r = sim.step();
          ASSERT_EQ(testing::intersectingTrianglePairs(sim.positions(), surface), 0) << name << ", step " << k;
          ASSERT_EQ(invertedTets(scene, sim.positions()), 0) << name << ", step " << k;
          excess = std::max(excess, r.energy.total() - r.target);
          kinetic = std::max(kinetic, r.energy.kinetic);
        }
        std::printf("two bars, %s: max(H - H*) / K_max %.4f\n", name, excess / kinetic);
        if (integrator == Integrator::EnergyBlend) {
          EXPECT_LE(excess, 0.05 * kinetic) << name;
        }
      }
    }
  }
}

// Steps `scene` (a cloth on a tet body) 60 times with `o`, expecting at every step that no surface
// triangle pair intersects and no tet inverts. Returns the largest H - H* over the blend's band
// tau = energy_tolerance (K + E_int + E_scale), and the positions at the end; prints it, and over
// the largest kinetic energy.
struct ClothOnBodyRun {
  double bands = 0.0;
  Eigen::MatrixX3d x;
};
ClothOnBodyRun dropClothOnBody(const Scene& scene, const SimulatorOptions& o, const std::string& name) {
  const std::vector<std::array<int, 3>> surface = ContactSurface::of(scene).triangles;
  Simulator sim(scene, o);
  double excess = 0.0, kinetic = 0.0, bands = 0.0;
  for (int k = 0; k < 60; ++k) {
    const StepReport& r = sim.step();
    const int crossing = testing::intersectingTrianglePairs(sim.positions(), surface);
    const int inverted = invertedTets(scene, sim.positions());
    EXPECT_EQ(crossing, 0) << name << ", step " << k;
    EXPECT_EQ(inverted, 0) << name << ", step " << k;
    if (crossing != 0 || inverted != 0) break;
    excess = std::max(excess, r.energy.total() - r.target);
    kinetic = std::max(kinetic, r.energy.kinetic);
    const double tau = testing::energyBand(sim, r);
    bands = std::max(bands, (r.energy.total() - r.target) / tau);
  }
  std::printf("%s: max(H - H*) / K_max %.4g, / tau %.3g\n", name.c_str(), excess / kinetic, bands);
  return ClothOnBodyRun{bands, sim.positions()};
}

// A cloth on a soft body (the case, a cloth on a tet body): a 30 x 30 cloth falling
// 20 cm onto a tet bar lying on the ground drapes over it, at rest and thrown at 5 and 12 m/s,
// with backward Euler and the blend. Without self-contact it falls through the bar.
// With it, over 60 steps: no surface triangle pair intersects and no tet inverts at any step,
// and the cloth stays over the bar (its highest point above the bar's). The default supports
// (SimulatorOptions::self_contact_supports 1: wherever the other side is the heavy bar, at any
// speed) hold the cloth's vertices against the bar's faces, and its triangles and edges against
// the bar's corners and edges, within the solve (docs/method.md, "Self-contact", "Within the
// solve"): the blend's H stays within the band tau = energy_tolerance (K + E_int + E_scale) of H*
// at every step, with half a band for what the pushes after the solve add and the velocities
// cannot pay (1.00, 0.98 and 1.18 tau measured at rest, 5 and 12 m/s; not at every speed: docs/
// results/method_measurements.md, "Within the solve: supports"). Without supports it runs
// 10, 165 and 116 tau above H*; with the cloth's vertices held on the bar's faces alone, and only
// in slow contact, it ran 1.2, 2.4 and 1.6, the bar's corners pushing through the cloth in the
// solve and the cloth sliding over the bar faster than the supports' reach.
TEST(SelfContactRun, AClothDropsOntoATetBarAndDrapesOverIt) {
  const std::vector<std::array<int, 3>> surface = ContactSurface::of(testing::clothOnBar()).triangles;
  const int cloth = 900;
  {
    Simulator sim(testing::clothOnBar(), SimulatorOptions{});
    int worst = 0;
    for (int k = 0; k < 40; ++k) {
      sim.step();
      worst = std::max(worst, testing::intersectingTrianglePairs(sim.positions(), surface));
    }
    EXPECT_GT(worst, 50);  // 279 measured
  }
  for (double speed : {0.0, 5.0, 12.0}) {
    for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend}) {
      Scene scene = testing::clothOnBar();
      scene.velocities.bottomRows(cloth).col(1).setConstant(-speed);
      SimulatorOptions o;
      o.integrator = integrator;
      o.self_contact_thickness = 5e-3;
      char name[64];
      std::snprintf(name, sizeof name, "cloth on a bar, %g m/s, %s", speed,
                    integrator == Integrator::BackwardEuler ? "BE" : "the blend");
      const ClothOnBodyRun run = dropClothOnBody(scene, o, name);
      if (integrator == Integrator::EnergyBlend) {
        EXPECT_LE(run.bands, 1.5) << name;
      }
      EXPECT_GT(run.x.col(1).tail(cloth).maxCoeff(), run.x.col(1).head(run.x.rows() - cloth).maxCoeff()) << name;
    }
  }
}

// The same drop on bodies and cloths of other kinds, with the blend: bars of 1e4, 1e5 and 1e7 Pa
// under cloths of one and thirty times the mass, thrown at 4 and 8 m/s (12 drops). Each stays
// within the band of the test above (1.5 tau; at most 1.40 measured with 4 mm). Where self-contact's
// pushes after the solve moved only the particles they touched, 4 of the 12 did not (2.0, 1.9, 8.5
// and 3.5 tau): a heavy cloth resting on a bar that springs back was pushed up where it touched,
// and the stretch around those particles kept up to 39 J that nothing booked. The elements now
// relax around the pushes (BatchDriver::relaxSelfContactPushes). Held only on the bar's faces and
// in slow contact, the soft, stiff and heavy drops ran 11, 2.5 and 31 tau above H*.
TEST(SelfContactRun, AClothOnSoftStiffAndHeavyVariantsKeepsTheBand) {
  const int cloth = 900;
  for (const double stiffness : {1e4, 1e5, 1e7}) {
    for (const double speed : {4.0, 8.0}) {
      for (const double cloth_mass : {1.0, 30.0}) {
        TetBarParams bar;
        bar.stiffness = stiffness;
        Scene scene = testing::clothOnBar(bar);
        scene.velocities.bottomRows(cloth).col(1).setConstant(-speed);
        scene.masses.tail(cloth) *= cloth_mass;
        SimulatorOptions o;
        o.self_contact_thickness = 4e-3;
        char name[96];
        std::snprintf(name, sizeof name, "a %g Pa bar under a cloth of %g times the mass at %g m/s", stiffness,
                      cloth_mass, speed);
        EXPECT_LE(dropClothOnBody(scene, o, name).bands, 1.5) << name;
      }
    }
  }
}

// A cloth ten times heavier than the cloth it lands on (clothOnCloth's upper one, 3 mm, the
// default supports: none in the solve between two cloths), thrown at 2, 4, 8 and 12 m/s: no
// crossing and H within 1.5 bands of H* at every step (1.08, 0.98, 1.00 and 0.89 measured). The
// pushes after the solve lift the heavy cloth where it touches, and before they relaxed through
// the elements it ran 144, 126, 74 and 146 bands above H*; at 2 m/s, with one round of relaxing
// 142, with three 5.
TEST(SelfContactRun, AHeavyClothOnAClothKeepsTheBand) {
  for (const double speed : {2.0, 4.0, 8.0, 12.0}) {
    Scene scene = clothOnCloth();
    const int upper = scene.numParticles() / 2;
    scene.velocities.bottomRows(upper).col(1).setConstant(-speed);
    scene.masses.tail(upper) *= 10.0;
    SimulatorOptions o;
    o.self_contact_thickness = 3e-3;
    char name[64];
    std::snprintf(name, sizeof name, "a heavy cloth on a cloth at %g m/s", speed);
    EXPECT_LE(dropClothOnBody(scene, o, name).bands, 1.5) << name;
  }
}

// A heavy body on a light one that a collider holds (the contact issue's other way round): a
// 62.5 kg tet bar dropped onto a 30 x 30 cloth lying on the ground, at rest and at 5 and 10 m/s,
// with the blend. No pair crosses and no tet inverts at any step, the bar ends above the cloth, and
// H stays within 1.5 bands of H* (1.07, 1.00 and 1.03 measured). The cloth's side takes no share
// of the approach stop (the ground holds it, the bar is heavy) and none of the push after the
// solve: shared by mass, they pushed the cloth into the ground and the bar went on through it,
// 11.5 bands above H* at rest and 770 at 10 m/s, and at 5 m/s the bar kept its 763 J and
// stretched the cloth to 170 J. The bar resting on the cloth stays where it rests: pushed by one
// sweep of growing impulses it was lifted 3.5 mm at every third step (2.7 bands), and with one
// rigid field over the bar and the cloth the blend's corrections moved the cloth under it. Not
// yet within the band: of tests/probe_bar_on_cloth's 28 drops, turned 0.2 and 0.3 rad at rest
// (1.7 bands) and 0.3 rad at 8 m/s, where the soft bar crumples against the ground (28 bands).
TEST(SelfContactRun, ATetBarDroppedOnAClothOnTheGroundRestsOnIt) {
  for (double speed : {0.0, 5.0, 10.0}) {
    const Scene scene = testing::barOnCloth(speed);
    SimulatorOptions o;
    o.self_contact_thickness = 4e-3;
    char name[64];
    std::snprintf(name, sizeof name, "a bar on a cloth, %g m/s", speed);
    const ClothOnBodyRun run = dropClothOnBody(scene, o, name);
    EXPECT_LE(run.bands, 1.5) << name;
    const int cloth = 900;
    EXPECT_GT(run.x.col(1).head(run.x.rows() - cloth).minCoeff(), run.x.col(1).tail(cloth).minCoeff()) << name;
  }
}

}  // namespace
}  // namespace stabint

namespace stabint {
namespace {

// Self-contact's supports act through a collider of their own (SceneSegment::support_collider),
// which the scene a Simulator shows does not list: its colliders are the user's.
TEST(SelfContactRun, TheSceneShownKeepsTheUsersColliders) {
  const Scene scene = testing::clothOnCloth();
  SimulatorOptions o;
  o.self_contact_thickness = 3e-3;
  o.self_contact_supports = 2;  // on the lower cloth too
  Simulator sim(scene, o);
  for (int k = 0; k < 6; ++k) sim.step();  // landed: supports in use
  ASSERT_EQ(sim.scene().colliders.size(), scene.colliders.size());
  EXPECT_EQ(sim.scene().colliders[0].shape, scene.colliders[0].shape);
  EXPECT_EQ(sim.scene().colliders[0].center, scene.colliders[0].center);
}

// Coulomb friction between the surfaces (SimulatorOptions::self_contact_friction): a cloth thrown
// sideways onto another lying on the ground (a 0.4 m cloth 2 cm above a 1 m one, at 1 m/s)
// slides farther without friction than with mu = 0.5, and the friction's loss is booked (BE's
// target never rises). Measured: its mean velocity after 30 steps is 0.56 m/s without friction
// and 0.38 m/s with it; the supports' normal impulses carry the cloth's weight, and their friction
// brakes it (asserted: at least 5 % slower).
TEST(SelfContactRun, FrictionBetweenTheSurfacesBrakesASlidingCloth) {
  Scene lower = testing::horizontalCloth(40, 0.002);
  ClothGridParams p;
  p.nx = p.ny = 20;
  p.width = p.height = 0.4;
  Scene upper = makeClothGrid(p);
  upper.pins.clear();
  for (int i = 0; i < upper.numParticles(); ++i) {
    const double u = upper.positions(i, 0), w = upper.positions(i, 1);
    upper.positions.row(i) << u - 0.45, 0.02, w - 0.2;
  }
  upper.rest_positions = upper.positions;
  Scene scene = testing::combined(lower, upper);
  const int n = upper.numParticles();
  scene.velocities.bottomRows(n).col(0).setConstant(1.0);
  scene.colliders = {testing::groundPlane(0.0, 1e4, 0.5)};
  double slide[2];
  for (int run = 0; run < 2; ++run) {
    SimulatorOptions o;
    o.integrator = Integrator::BackwardEuler;
    o.self_contact_thickness = 3e-3;
    o.self_contact_supports = 2;  // on the lower cloth too
    o.self_contact_friction = run == 0 ? 0.0 : 0.5;
    Simulator sim(scene, o);
    double target = sim.target();
    for (int k = 0; k < 30; ++k) {
      const StepReport& r = sim.step();
      EXPECT_LE(r.target, target + 1e-12) << "step " << k;
      target = r.target;
    }
    slide[run] = sim.velocities().col(0).tail(n).mean();
  }
  std::printf("the upper cloth's mean velocity after 30 steps: %.3f m/s without friction, %.3f with mu 0.5\n", slide[0],
              slide[1]);
  EXPECT_LT(slide[1], 0.95 * slide[0]);
}

}  // namespace
}  // namespace stabint
