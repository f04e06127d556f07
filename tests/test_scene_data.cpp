// SceneData precomputation (tet rest data, contribution CSR, forcing queries) and the scene's
// geometric helpers (rest volume, mass lumping, cloth springs, pin and force-field time laws).
#include <stabint/errors.hpp>
#include <stabint/scene.hpp>

#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

namespace stabint {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Two tets sharing the face (1, 2, 3), a spring and two pins: every contribution kind appears,
// and vertices 1..3 collect contributions from several elements.
Scene twoTetScene() {
  Scene s;
  s.rest_positions.resize(6, 3);
  s.rest_positions << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 3, 0, 0;
  s.positions = s.rest_positions;
  s.velocities = Eigen::MatrixX3d::Zero(6, 3);
  s.masses = Eigen::VectorXd::LinSpaced(6, 1.0, 6.0);
  s.springs = {Spring{5, 1, 2.0, 10.0}, Spring{0, 5, 3.0, 20.0}};
  s.tets = {Tet{{0, 1, 2, 3}, 100.0}, Tet{{4, 1, 3, 2}, 200.0}};
  Pin a;
  a.vertex = 0;
  a.stiffness = 1e3;
  Pin b;
  b.vertex = 5;
  b.stiffness = 1e3;
  b.target.position = Eigen::Vector3d(3, 0, 0);
  s.pins = {a, b};
  s.gravity = Eigen::Vector3d(0, -10, 0);
  return s;
}

TEST(SceneGeometry, SignedVolumeOfTheUnitCornerTet) {
  Eigen::MatrixX3d x(4, 3);
  x << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  EXPECT_DOUBLE_EQ(signedVolume(x, {0, 1, 2, 3}), 1.0 / 6.0);
  EXPECT_DOUBLE_EQ(signedVolume(x, {0, 2, 1, 3}), -1.0 / 6.0);
}

const ElementBlock& blockNamed(const SceneData& data, const std::string& name) {
  for (const ElementBlock& block : data.blocks())
    if (name == block.type->name()) return block;
  throw std::runtime_error("no block " + name);
}

// The tet block: A_e maps the rest positions of its vertices to F^T = I, and w = k V.
TEST(SceneData, TetBlockMapsTheRestShapeToIdentityAndWeighsByVolume) {
  const Scene s = twoTetScene();
  const SceneData data(s);
  const ElementBlock& tets = blockNamed(data, "tet");
  ASSERT_EQ(tets.count, 2);
  ASSERT_EQ(tets.coefficients.size(), 2u * 12u);
  ASSERT_EQ(tets.params.size(), 2u);
  for (int e = 0; e < 2; ++e) {
    const std::array<int, 4>& v = s.tets[e].vertices;
    EXPECT_EQ(std::vector<int>(tets.vertices.begin() + 4 * e, tets.vertices.begin() + 4 * e + 4),
              std::vector<int>(v.begin(), v.end()));
    const Eigen::Map<const Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> a(&tets.coefficients[12 * e]);
    Eigen::Matrix<double, 4, 3> x;
    for (int k = 0; k < 4; ++k) x.row(k) = s.rest_positions.row(v[k]);
    EXPECT_TRUE((a * x).isIdentity(1e-12)) << a * x;
    EXPECT_NEAR(tets.params[e], s.tets[e].stiffness * signedVolume(s.rest_positions, v), 1e-12);
  }
  EXPECT_NEAR(tets.params[0], 100.0 / 6.0, 1e-12);
}

TEST(SceneData, ContributionCsrFollowsTheDocumentedNumbering) {
  const SceneData data(twoTetScene());
  const ContributionCsr& csr = data.csr();
  EXPECT_EQ(blockNamed(data, "spring").contribution_base, 0);
  EXPECT_EQ(blockNamed(data, "tet").contribution_base, 4);
  EXPECT_EQ(blockNamed(data, "pin").contribution_base, 12);
  EXPECT_EQ(csr.numContributions, 14);
  ASSERT_EQ(csr.offsets.size(), 7u);
  EXPECT_EQ(csr.offsets.front(), 0);
  EXPECT_EQ(csr.offsets.back(), 14);
  const auto list = [&](int v) {
    return std::vector<int>(csr.contributions.begin() + csr.offsets[v], csr.contributions.begin() + csr.offsets[v + 1]);
  };
  // spring 0 = (5, 1): 0 -> 5, 1 -> 1; spring 1 = (0, 5): 2 -> 0, 3 -> 5;
  // tet 0 = (0,1,2,3): 4..7; tet 1 = (4,1,3,2): 8..11; pin 0 -> 0: 12; pin 1 -> 5: 13.
  EXPECT_EQ(list(0), (std::vector<int>{2, 4, 12}));
  EXPECT_EQ(list(1), (std::vector<int>{1, 5, 9}));
  EXPECT_EQ(list(2), (std::vector<int>{6, 11}));
  EXPECT_EQ(list(3), (std::vector<int>{7, 10}));
  EXPECT_EQ(list(4), (std::vector<int>{8}));
  EXPECT_EQ(list(5), (std::vector<int>{0, 3, 13}));
}

TEST(Forcing, ExternalForcesAddFieldsToGravity) {
  Scene s = twoTetScene();
  ForceField everywhere;
  everywhere.force = Eigen::Vector3d(1, 0, 0);
  ForceField growing;
  growing.particles = {2, 4};
  growing.rate = Eigen::Vector3d(0, 0, 2);
  growing.amplitude = Eigen::Vector3d(0, 1, 0);
  growing.frequency = 0.25;
  s.force_fields = {everywhere, growing};
  const Forcing forcing(s);
  Eigen::MatrixX3d f;
  forcing.externalForces(1.0, f);
  ASSERT_EQ(f.rows(), 6);
  for (int j = 0; j < 6; ++j) {
    const bool in_field = j == 2 || j == 4;
    // sin(2 pi 0.25 1) = 1
    const Eigen::RowVector3d expected(1.0, -10.0 * s.masses[j] + (in_field ? 1.0 : 0.0), in_field ? 2.0 : 0.0);
    EXPECT_TRUE(f.row(j).isApprox(expected, 1e-12)) << "particle " << j << ": " << f.row(j);
  }
  EXPECT_TRUE(forcing.hasTimeDependentForces());
  EXPECT_FALSE(forcing.hasMovingPins());
}

TEST(Forcing, PinTargetsFollowTheirTimeLaw) {
  Scene s = twoTetScene();
  s.pins[1].target.velocity = Eigen::Vector3d(0, 1, 0);
  s.pins[1].target.amplitude = Eigen::Vector3d(0, 0, 0.5);
  s.pins[1].target.frequency = 1.0;
  const Forcing forcing(s);
  EXPECT_TRUE(forcing.pinTarget(0, 0.25).isZero());
  EXPECT_TRUE(forcing.pinTarget(1, 0.25).isApprox(Eigen::Vector3d(3.0, 0.25, 0.5), 1e-12));
  EXPECT_TRUE(forcing.hasMovingPins());
  EXPECT_FALSE(forcing.hasTimeDependentForces());
}

TEST(Forcing, StaticSceneHasNoTimeDependentForcing) {
  const Scene s = twoTetScene();
  const Forcing forcing(s);
  EXPECT_FALSE(forcing.hasMovingPins());
  EXPECT_FALSE(forcing.hasTimeDependentForces());
  EXPECT_FALSE(forcing.hasMovingColliders());
}

// Per scene of a batch: only the scenes whose own pins, fields, user forces or colliders change
// over [t0, t1] are forced (the driver keeps L-BFGS's rigid motions out of those scenes'
// implicit-midpoint solves).
TEST(Forcing, ChangesPerSceneOfABatch) {
  std::vector<Scene> scenes(5, twoTetScene());
  scenes[1].pins[1].target.velocity = Eigen::Vector3d(0, 1, 0);  // a moving pin law
  ForceField local;
  local.particles = {2};
  local.rate = Eigen::Vector3d(0, 0, 1);
  scenes[2].force_fields = {local};
  Collider plane;
  plane.center = Eigen::Vector3d(0, -1, 0);
  scenes[3].colliders = {plane};
  scenes[4].colliders = {plane};
  scenes[4].colliders[0].velocity = Eigen::Vector3d(0, 0.1, 0);  // a moving collider law
  const SceneBatch batch = concatenateScenes(scenes);
  Forcing forcing(batch.scene);
  const double h = 0.01;
  using Flags = std::vector<char>;
  EXPECT_EQ(forcing.changesDuring(0.0, h, batch.segments), (Flags{0, 1, 1, 0, 1}));

  // Run-time ramps over [h, 2h]: scene 0's user forces, scene 3's pin and collider.
  const SceneSegment& s0 = batch.segments[0];
  forcing.rampUserForceRows(s0.first_particle, Eigen::MatrixX3d::Ones(s0.num_particles, 3), h, 2 * h);
  EXPECT_EQ(forcing.changesDuring(h, 2 * h, batch.segments), (Flags{1, 1, 1, 0, 1}));
  forcing.rampPinTarget(2 * 3 + 1, Eigen::Vector3d(1, 2, 3), h, 2 * h);  // scene 3's second pin
  EXPECT_EQ(forcing.changesDuring(h, 2 * h, batch.segments), (Flags{1, 1, 1, 1, 1}));
  // After the ramps' end only the laws move.
  EXPECT_EQ(forcing.changesDuring(2 * h, 3 * h, batch.segments), (Flags{0, 1, 1, 0, 1}));
  forcing.rampColliderPosition(batch.segments[3].first_collider, Eigen::Vector3d(0, -0.5, 0), 3 * h, 4 * h);
  EXPECT_EQ(forcing.changesDuring(3 * h, 4 * h, batch.segments), (Flags{0, 1, 1, 1, 1}));

  // A scene's field without a particle list acts on its own particles in a batch, on every
  // particle of a Simulator's scene.
  std::vector<Scene> with_wind = scenes;
  ForceField wind;
  wind.rate = Eigen::Vector3d(1, 0, 0);
  with_wind[0].force_fields = {wind};
  const SceneBatch windy = concatenateScenes(with_wind);
  EXPECT_EQ(Forcing(windy.scene).changesDuring(0.0, h, windy.segments), (Flags{1, 1, 1, 0, 1}));
  const SceneBatch alone = batchOfOne(with_wind[0]);
  EXPECT_EQ(Forcing(alone.scene).changesDuring(0.0, h, alone.segments), (Flags{1}));
  EXPECT_EQ(Forcing(scenes[0]).changesDuring(0.0, h, batchOfOne(scenes[0]).segments), (Flags{0}));
}

TEST(SceneTimeLaws, OscillationNeedsBothAmplitudeAndFrequency) {
  PinTarget pin;
  pin.position = Eigen::Vector3d(1, 2, 3);
  EXPECT_FALSE(pin.moving());
  pin.amplitude = Eigen::Vector3d(1, 0, 0);
  EXPECT_FALSE(pin.moving());  // sin(0) = 0 at every t
  pin.frequency = 2.0;
  EXPECT_TRUE(pin.moving());
  EXPECT_NEAR(pin.at(1.0 / 8.0).x(), 2.0, 1e-12);
  EXPECT_NEAR(pin.at(0.5).x(), 1.0, 1e-12);

  ForceField field;
  field.force = Eigen::Vector3d(0, 0, 4);
  EXPECT_FALSE(field.timeDependent());
  field.rate = Eigen::Vector3d(0, -1, 0);
  EXPECT_TRUE(field.timeDependent());
  EXPECT_TRUE(field.at(3.0).isApprox(Eigen::Vector3d(0, -3, 4)));
  field.rate.setZero();
  field.amplitude = Eigen::Vector3d(2, 0, 0);
  field.frequency = 1.0;
  EXPECT_TRUE(field.timeDependent());
  EXPECT_NEAR(field.at(0.25).x(), 2.0 * std::sin(2.0 * kPi * 0.25), 1e-12);
}

TEST(SceneGeometry, LumpedMassesConserveTotalsAndFillUntouchedParticles) {
  Eigen::MatrixX3d x(5, 3);
  x << 0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 2, 9, 9, 9;
  const Eigen::VectorXd tet_masses = lumpMassesFromTets(x, {Tet{{0, 1, 2, 3}, 1.0}}, 3.0, 1e-4);
  EXPECT_NEAR(tet_masses.head(4).sum(), 3.0 * 8.0 / 6.0, 1e-12);
  EXPECT_NEAR(tet_masses[1], 1.0, 1e-12);
  EXPECT_EQ(tet_masses[4], 1e-4);
  const Eigen::VectorXd tri_masses = lumpMassesFromTriangles(x, {{0, 1, 2}}, 0.5);
  EXPECT_NEAR(tri_masses.head(3).sum(), 0.5 * 2.0, 1e-12);
  EXPECT_EQ(tri_masses[3], 1e-6);
  EXPECT_THROW(lumpMassesFromTriangles(x, {{0, 1, 5}}, 1.0), InvalidInputError);
  EXPECT_THROW(lumpMassesFromTets(x, {Tet{{0, 1, 2, -1}, 1.0}}, 1.0), InvalidInputError);
}

TEST(SceneGeometry, ClothSpringsOfTwoTrianglesAreFiveEdgesAndOneHinge) {
  Eigen::MatrixX3d x(4, 3);
  x << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  const auto springs = clothSpringsFromTriangles(x, {{0, 1, 2}, {0, 2, 3}}, 10.0, 1.0);
  ASSERT_EQ(springs.size(), 6u);
  std::set<std::pair<int, int>> structural;
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(springs[i].stiffness, 10.0);
    EXPECT_LT(springs[i].a, springs[i].b);
    structural.emplace(springs[i].a, springs[i].b);
    EXPECT_NEAR(springs[i].rest_length, (x.row(springs[i].a) - x.row(springs[i].b)).norm(), 1e-15);
  }
  EXPECT_EQ(structural, (std::set<std::pair<int, int>>{{0, 1}, {1, 2}, {0, 2}, {2, 3}, {0, 3}}));
  EXPECT_EQ(springs[5].a, 1);
  EXPECT_EQ(springs[5].b, 3);
  EXPECT_EQ(springs[5].stiffness, 1.0);
  EXPECT_NEAR(springs[5].rest_length, std::sqrt(2.0), 1e-15);
}

TEST(SceneGeometry, ClothSpringOrderDoesNotDependOnTriangleOrder) {
  Eigen::MatrixX3d x(5, 3);
  x << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 0.2;
  std::vector<std::array<int, 3>> fan = {{4, 0, 1}, {4, 1, 2}, {4, 2, 3}, {4, 3, 0}};
  const auto a = clothSpringsFromTriangles(x, fan, 1.0, 0.1);
  std::reverse(fan.begin(), fan.end());
  std::swap(fan[0][1], fan[0][2]);
  const auto b = clothSpringsFromTriangles(x, fan, 1.0, 0.1);
  ASSERT_EQ(a.size(), b.size());
  // 8 edges; hinges across the 4 spokes join 0-2 and 1-3 twice each, kept once.
  EXPECT_EQ(a.size(), 8u + 2u);
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].a, b[i].a);
    EXPECT_EQ(a[i].b, b[i].b);
  }
}

}  // namespace
}  // namespace stabint
