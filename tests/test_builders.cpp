// Built-in scenes: counts, geometry, masses, pins, and that each passes validateScene.
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <functional>
#include <map>
#include <string>

namespace stabint {
namespace {

using ::testing::HasSubstr;

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidInputError& e) {
    return e.what();
  }
  return "<no error>";
}

TEST(Builders, LinearOscillator) {
  const Scene s = makeLinearOscillator({2.0, 50.0, 0.3});
  EXPECT_EQ(s.name, "oscillator");
  ASSERT_EQ(s.numParticles(), 1);
  EXPECT_TRUE(s.positions.row(0).isApprox(Eigen::RowVector3d(0.3, 0, 0)));
  EXPECT_EQ(s.rest_positions, s.positions);
  EXPECT_TRUE(s.velocities.isZero());
  EXPECT_EQ(s.masses[0], 2.0);
  EXPECT_TRUE(s.gravity.isZero());
  ASSERT_EQ(s.pins.size(), 1u);
  EXPECT_EQ(s.pins[0].vertex, 0);
  EXPECT_EQ(s.pins[0].stiffness, 50.0);
  EXPECT_TRUE(s.pins[0].target.position.isZero());
  EXPECT_FALSE(s.pins[0].target.moving());
  EXPECT_TRUE(s.springs.empty());
  EXPECT_TRUE(s.tets.empty());
  EXPECT_NO_THROW(validateScene(s));
}

TEST(Builders, ChainPendulumIsTheSpecsStiffChain) {
  const Scene s = makeChainPendulum();
  EXPECT_EQ(s.name, "chain");
  ASSERT_EQ(s.numParticles(), 10);
  ASSERT_EQ(s.springs.size(), 9u);
  EXPECT_NEAR(s.masses.sum(), 0.1, 1e-15);
  EXPECT_TRUE(s.masses.isConstant(0.01));
  for (int i = 0; i < 10; ++i) {
    EXPECT_NEAR(s.positions(i, 0), i / 9.0, 1e-15);
    EXPECT_EQ(s.positions(i, 1), 0.0);
    EXPECT_EQ(s.positions(i, 2), 0.0);
  }
  for (int i = 0; i < 9; ++i) {
    EXPECT_EQ(s.springs[i].a, i);
    EXPECT_EQ(s.springs[i].b, i + 1);
    EXPECT_NEAR(s.springs[i].rest_length, 1.0 / 9.0, 1e-15);
    EXPECT_EQ(s.springs[i].stiffness, 1e4);
  }
  ASSERT_EQ(s.pins.size(), 1u);
  EXPECT_EQ(s.pins[0].vertex, 0);
  EXPECT_TRUE(s.pins[0].target.position.isZero());
  EXPECT_EQ(s.pins[0].stiffness, 1e6);
  EXPECT_TRUE(s.gravity.isApprox(Eigen::Vector3d(0, -9.81, 0)));
  EXPECT_TRUE(s.velocities.isZero());
  EXPECT_NO_THROW(validateScene(s));
}

// Structural nx-1 per row and ny-1 per column, two shears per cell, bending two apart.
size_t expectedClothSprings(int nx, int ny) {
  return static_cast<size_t>(ny * (nx - 1) + nx * (ny - 1) + 2 * (nx - 1) * (ny - 1) + ny * (nx - 2) + nx * (ny - 2));
}

TEST(Builders, ClothGrid50x50) {
  ClothGridParams p;
  p.nx = 50;
  p.ny = 50;
  p.width = 2.0;
  p.height = 1.5;
  p.areal_density = 0.3;
  const Scene s = makeClothGrid(p);
  EXPECT_EQ(s.name, "cloth");
  EXPECT_EQ(s.numParticles(), 2500);
  EXPECT_EQ(s.springs.size(), 14502u);
  EXPECT_EQ(s.springs.size(), expectedClothSprings(50, 50));
  EXPECT_NEAR(s.masses.sum(), 0.3 * 2.0 * 1.5, 1e-12);
  EXPECT_TRUE(s.tets.empty());
  // Top row j = 0 at y = height; the default pins are its two corners.
  EXPECT_TRUE(s.positions.row(0).isApprox(Eigen::RowVector3d(0, 1.5, 0)));
  EXPECT_TRUE(s.positions.row(49).isApprox(Eigen::RowVector3d(2.0, 1.5, 0)));
  EXPECT_NEAR(s.positions(2499, 1), 0.0, 1e-15);
  ASSERT_EQ(s.pins.size(), 2u);
  EXPECT_EQ(s.pins[0].vertex, 0);
  EXPECT_EQ(s.pins[1].vertex, 49);
  EXPECT_TRUE(s.pins[1].target.position.isApprox(s.positions.row(49).transpose()));
  ASSERT_EQ(s.bodies.size(), 1u);
  EXPECT_EQ(s.bodies[0].particles.size(), 2500u);
  EXPECT_NO_THROW(validateScene(s));
}

TEST(Builders, ClothSpringKindsAndRestLengths) {
  ClothGridParams p;
  p.nx = 4;
  p.ny = 3;
  p.width = 3.0;   // dx = 1
  p.height = 1.0;  // dy = 0.5
  p.damping = 0.2;
  p.pinned = {5, 6};
  const Scene s = makeClothGrid(p);
  ASSERT_EQ(s.springs.size(), expectedClothSprings(4, 3));
  std::map<double, int> by_stiffness;
  for (const Spring& sp : s.springs) {
    ++by_stiffness[sp.stiffness];
    EXPECT_NEAR(sp.rest_length, (s.rest_positions.row(sp.a) - s.rest_positions.row(sp.b)).norm(), 1e-15);
  }
  EXPECT_EQ(by_stiffness[p.stretch_stiffness], 3 * 3 + 4 * 2);
  EXPECT_EQ(by_stiffness[p.shear_stiffness], 2 * 3 * 2);
  EXPECT_EQ(by_stiffness[p.bend_stiffness], 3 * 2 + 4 * 1);
  ASSERT_EQ(s.pins.size(), 2u);
  EXPECT_EQ(s.pins[0].vertex, 5);
  EXPECT_TRUE(s.pins[0].target.position.isApprox(Eigen::Vector3d(1.0, 0.5, 0)));
  EXPECT_EQ(s.bodies[0].damping, 0.2);
  // Interior particles carry a full share of the area, corners a sixth of a cell's.
  EXPECT_GT(s.masses[5], s.masses[0]);
}

TEST(Builders, TetBarMassVolumesPinsAndConformingFaces) {
  TetBarParams p;
  p.nx = 4;
  p.ny = 2;
  p.nz = 3;
  p.length = 2.0;
  p.width = 0.3;
  p.density = 500.0;
  p.damping = 0.05;
  const Scene s = makeTetBar(p);
  EXPECT_EQ(s.name, "tetbar");
  EXPECT_EQ(s.numParticles(), 5 * 3 * 4);
  ASSERT_EQ(s.tets.size(), 6u * 4 * 2 * 3);
  EXPECT_NEAR(s.masses.sum(), 500.0 * 2.0 * 0.3 * 0.3, 1e-9);
  const double cell = (2.0 / 4) * (0.3 / 2) * (0.3 / 3);
  for (const Tet& t : s.tets) EXPECT_NEAR(signedVolume(s.rest_positions, t.vertices), cell / 6.0, 1e-15);
  EXPECT_EQ(s.positions.col(0).minCoeff(), 0.0);
  EXPECT_NEAR(s.positions.col(0).maxCoeff(), 2.0, 1e-15);
  EXPECT_NEAR(s.positions.col(1).maxCoeff(), 0.3, 1e-15);
  EXPECT_NEAR(s.positions.col(2).maxCoeff(), 0.3, 1e-15);

  // Pinned: exactly the particles at x = 0, in place.
  ASSERT_EQ(s.pins.size(), 3u * 4);
  for (const Pin& pin : s.pins) {
    EXPECT_EQ(s.positions(pin.vertex, 0), 0.0);
    EXPECT_TRUE(pin.target.position.isApprox(s.positions.row(pin.vertex).transpose()));
    EXPECT_EQ(pin.stiffness, p.pin_stiffness);
  }

  // Conforming: every triangle is shared by two tets inside and used once on the boundary,
  // where each of the boundary squares is split into two triangles.
  std::map<std::array<int, 3>, int> faces;
  for (const Tet& t : s.tets) {
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> f{};
      for (int k = 0, m = 0; k < 4; ++k) {
        if (k != skip) f[m++] = t.vertices[k];
      }
      std::sort(f.begin(), f.end());
      ++faces[f];
    }
  }
  int boundary = 0;
  for (const auto& [face, count] : faces) {
    EXPECT_LE(count, 2);
    boundary += count == 1;
  }
  EXPECT_EQ(boundary, 2 * 2 * (4 * 2 + 2 * 3 + 4 * 3));

  EXPECT_TRUE(s.gravity.isApprox(Eigen::Vector3d(0, -9.81, 0)));
  EXPECT_EQ(s.bodies[0].damping, 0.05);
  EXPECT_NO_THROW(validateScene(s));
}

TEST(Builders, DefaultScenesPassValidation) {
  EXPECT_NO_THROW(validateScene(makeLinearOscillator()));
  EXPECT_NO_THROW(validateScene(makeChainPendulum()));
  EXPECT_NO_THROW(validateScene(makeClothGrid()));
  EXPECT_NO_THROW(validateScene(makeTetBar()));
}

TEST(Builders, BadParametersAreRejectedWithTheirName) {
  EXPECT_THAT(messageOf([] { makeChainPendulum({1}); }), HasSubstr("chain particles = 1 must be >= 2"));
  EXPECT_THAT(messageOf([] {
                ClothGridParams p;
                p.ny = 1;
                makeClothGrid(p);
              }),
              HasSubstr("cloth ny = 1 must be >= 2"));
  EXPECT_THAT(messageOf([] {
                TetBarParams p;
                p.nz = 0;
                makeTetBar(p);
              }),
              HasSubstr("tet bar nz = 0 must be >= 1"));
  EXPECT_THAT(messageOf([] {
                ClothGridParams p;
                p.pinned = {3, 400};
                makeClothGrid(p);
              }),
              HasSubstr("pin 1: index vertex = 400 out of range [0, 400)"));
  EXPECT_THAT(messageOf([] { makeLinearOscillator({0.0, 1.0, 1.0}); }), HasSubstr("masses[0] = 0 must be > 0"));
  EXPECT_THAT(messageOf([] {
                ClothGridParams p;
                p.damping = 2.0;
                makeClothGrid(p);
              }),
              HasSubstr("body 'cloth': damping 2 outside [0, 1]"));
  EXPECT_THAT(messageOf([] {
                TetBarParams p;
                p.stiffness = -1.0;
                makeTetBar(p);
              }),
              HasSubstr("tet 0: stiffness -1 must be >= 0"));
}

// A cloth of zero width (or one whose edges underflow) has flat triangles, which lump no mass:
// refused, where the spring cloth once stepped made-up 1e-6 kg particles on zero-length springs.
TEST(Builders, FlatClothAndFlatTrianglesAreRefused) {
  for (double width : {0.0, 1e-200}) {
    SCOPED_TRACE(width);
    for (ClothModel model : {ClothModel::Springs, ClothModel::Triangles}) {
      ClothGridParams p;
      p.width = width;
      p.model = model;
      EXPECT_THAT(messageOf([&] { makeClothGrid(p); }), HasSubstr("triangle 0: degenerate rest triangle (0, 20, 1)"));
    }
  }
  const Eigen::MatrixX3d collinear = (Eigen::MatrixX3d(3, 3) << 0, 0, 0, 1, 0, 0, 2, 0, 0).finished();
  EXPECT_THAT(messageOf([&] {
                lumpMassesFromTriangles(collinear, {{0, 1, 2}}, 1.0);
              }),
              HasSubstr("triangle 0: degenerate rest triangle (0, 1, 2), area 0"));
  // A particle in no triangle still gets min_mass.
  const Eigen::MatrixX3d four = (Eigen::MatrixX3d(4, 3) << 0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5).finished();
  const Eigen::VectorXd m = lumpMassesFromTriangles(four, {{0, 1, 2}}, 3.0, 1e-6);
  EXPECT_DOUBLE_EQ(m[0], 0.5);  // 3 kg/m^2 x 0.5 m^2 / 3
  EXPECT_EQ(m[3], 1e-6);
}

}  // namespace
}  // namespace stabint
