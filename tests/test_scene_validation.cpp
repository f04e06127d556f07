// validateScene: every rule rejects its violation with a message that names the element or field.
#include <stabint/errors.hpp>
#include <stabint/scene.hpp>

#include "scene/scene_data.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

namespace stabint {
namespace {

using ::testing::HasSubstr;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Five particles: a unit right-angle tet (0..3) and a fifth particle on a spring; one of each
// element kind, a force field and a body, so every rule has something to break.
Scene validScene() {
  Scene s;
  s.name = "probe";
  s.rest_positions.resize(5, 3);
  s.rest_positions << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 2, 0, 0;
  s.positions = s.rest_positions;
  s.velocities = Eigen::MatrixX3d::Zero(5, 3);
  s.masses = Eigen::VectorXd::Constant(5, 0.5);
  s.springs.push_back(Spring{1, 4, 1.0, 100.0});
  s.springs.push_back(Spring{0, 1, 1.0, 100.0});
  s.tets.push_back(Tet{{0, 1, 2, 3}, 1e3});
  s.triangle_strains.push_back(TriangleStrain{{0, 1, 2}, 10.0, 0.9, 1.1});
  // Edge 1-2 with particle 0 on one side and particle 4 on the other, all in the plane z = 0.
  s.bending_hinges.push_back(BendingHinge{{1, 2, 0, 4}, 0.1});
  s.triangles.push_back({0, 1, 2});
  Pin pin;
  pin.vertex = 0;
  pin.stiffness = 1e4;
  s.pins.push_back(pin);
  ForceField field;
  field.particles = {2, 3};
  field.force = Eigen::Vector3d(1, 0, 0);
  s.force_fields.push_back(field);
  s.bodies.push_back(Body{"cloth", {0, 1, 2, 3, 4}, 0.1});
  return s;
}

// The message of the InvalidInputError that validating the edited scene throws.
std::string messageAfter(const std::function<void(Scene&)>& edit) {
  Scene s = validScene();
  edit(s);
  try {
    validateScene(s);
  } catch (const InvalidInputError& e) {
    return e.what();
  }
  return "<no error>";
}

TEST(SceneValidation, ValidSceneAndItsElementsPass) {
  EXPECT_NO_THROW(validateScene(validScene()));
  // Zero stiffness, zero rest length and the damping bounds themselves are allowed.
  EXPECT_EQ(messageAfter([](Scene& s) {
              s.springs[0].stiffness = 0.0;
              s.springs[0].rest_length = 0.0;
              s.bodies[0].damping = 1.0;
              s.pins[0].stiffness = 0.0;
            }),
            "<no error>");
}

TEST(SceneValidation, EmptySceneIsRejected) {
  EXPECT_THAT(messageAfter([](Scene& s) { s = Scene{}; }), HasSubstr("has no particles"));
}

TEST(SceneValidation, ShapeMismatchesNameTheField) {
  EXPECT_THAT(messageAfter([](Scene& s) { s.rest_positions.conservativeResize(4, 3); }),
              HasSubstr("rest_positions has 4 rows but positions has 5"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.velocities.resize(6, 3); }),
              HasSubstr("velocities has 6 rows but positions has 5"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.masses.resize(3); }),
              HasSubstr("masses has 3 entries but positions has 5 rows"));
}

TEST(SceneValidation, NonFiniteParticleDataNamesTheRow) {
  EXPECT_THAT(messageAfter([](Scene& s) { s.positions(3, 1) = kNaN; }), HasSubstr("positions row 3 is not finite"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.rest_positions(2, 0) = kInf; }),
              HasSubstr("rest_positions row 2 is not finite"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.velocities(4, 2) = -kInf; }), HasSubstr("velocities row 4 is not finite"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.gravity.y() = kNaN; }), HasSubstr("gravity (0, nan, 0) is not finite"));
}

TEST(SceneValidation, MassesMustBePositiveAndFinite) {
  EXPECT_THAT(messageAfter([](Scene& s) { s.masses[4] = 0.0; }), HasSubstr("masses[4] = 0 must be > 0"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.masses[1] = -2.0; }), HasSubstr("masses[1] = -2 must be > 0"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.masses[2] = kNaN; }), HasSubstr("masses[2] = nan"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.masses[2] = kInf; }), HasSubstr("masses[2] = inf"));
}

TEST(SceneValidation, SpringRules) {
  EXPECT_THAT(messageAfter([](Scene& s) { s.springs[1].b = 57; }),
              HasSubstr("spring 1: index b = 57 out of range [0, 5)"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.springs[0].a = -1; }),
              HasSubstr("spring 0: index a = -1 out of range [0, 5)"));
  EXPECT_THAT(messageAfter([](Scene& s) {
                s.springs[1] = Spring{3, 3, 0.0, 1.0};
              }),
              HasSubstr("spring 1 joins particle 3 to itself"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.springs[0].rest_length = -0.5; }),
              HasSubstr("spring 0: rest length -0.5 must be >= 0"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.springs[0].rest_length = kNaN; }), HasSubstr("spring 0: rest length nan"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.springs[1].stiffness = -1.0; }),
              HasSubstr("spring 1: stiffness -1 must be >= 0"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.springs[1].stiffness = kInf; }),
              HasSubstr("spring 1: stiffness inf must be >= 0"));
}

TEST(SceneValidation, TetRules) {
  EXPECT_THAT(messageAfter([](Scene& s) { s.tets[0].vertices[2] = 9; }),
              HasSubstr("tet 0: index vertices[2] = 9 out of range [0, 5)"));
  EXPECT_THAT(messageAfter([](Scene& s) {
                s.tets[0].vertices = {0, 1, 2, 1};
              }),
              HasSubstr("tet 0: particle 1 appears twice"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.tets[0].stiffness = -3.0; }),
              HasSubstr("tet 0: stiffness -3 must be >= 0"));
  // Swapping two vertices inverts the tet: volume -1/6.
  EXPECT_THAT(messageAfter([](Scene& s) {
                s.tets[0].vertices = {0, 2, 1, 3};
              }),
              HasSubstr("tet 0: negative rest volume -0.166667 (inverted: list two vertices in the other order)"));
  // A flat tet: the apex moved into the base plane.
  EXPECT_THAT(messageAfter([](Scene& s) { s.rest_positions.row(3) << 0.3, 0.3, 0.0; }),
              HasSubstr("tet 0: zero rest volume 0 for its longest edge L = 1.41421 (degenerate: at most 1e-12 L^3)"));
}

TEST(SceneValidation, TetVolumeUsesRestPositionsNotPositions) {
  EXPECT_NO_THROW(validateScene([] {
    Scene s = validScene();
    s.positions.row(3) << 0, 0, -1;  // the current shape may be inverted
    return s;
  }()));
}

TEST(SceneValidation, TriangleStrainRules) {
  EXPECT_THAT(messageAfter([](Scene& s) { s.triangle_strains[0].vertices[1] = 9; }),
              HasSubstr("triangle strain 0: index vertices[1] = 9 out of range [0, 5)"));
  EXPECT_THAT(messageAfter([](Scene& s) {
                s.triangle_strains[0].vertices = {0, 1, 0};
              }),
              HasSubstr("triangle strain 0: particle 0 appears twice (vertices[0] and vertices[2])"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.triangle_strains[0].stiffness = -2.0; }),
              HasSubstr("triangle strain 0: stiffness -2 must be >= 0"));
  // Particles 0, 1 and 4 lie on the x axis.
  EXPECT_THAT(messageAfter([](Scene& s) {
                s.triangle_strains.push_back(TriangleStrain{{0, 1, 4}, 1.0});
              }),
              HasSubstr("triangle strain 1: degenerate rest triangle (0, 1, 4), area 0"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.triangle_strains[0].strain_min = 1.2; }),
              HasSubstr("triangle strain 0: strain limits [1.2, 1.1] must satisfy 0 <= strain_min <= 1 <= strain_max"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.triangle_strains[0].strain_max = kInf; }),
              HasSubstr("triangle strain 0: strain limits [0.9, inf]"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.triangle_strains[0].strain_min = kNaN; }),
              HasSubstr("triangle strain 0: strain limits [nan, 1.1]"));
  // Only the rest shape counts: the current one may be degenerate or flipped.
  EXPECT_EQ(messageAfter([](Scene& s) { s.positions.row(2) << 1, 0, 0; }), "<no error>");
}

TEST(SceneValidation, BendingHingeRules) {
  EXPECT_THAT(messageAfter([](Scene& s) { s.bending_hinges[0].vertices[3] = -1; }),
              HasSubstr("bending hinge 0: index vertices[3] = -1 out of range [0, 5)"));
  EXPECT_THAT(messageAfter([](Scene& s) {
                s.bending_hinges[0].vertices = {1, 2, 0, 2};
              }),
              HasSubstr("bending hinge 0: particle 2 appears twice"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.bending_hinges[0].stiffness = kNaN; }),
              HasSubstr("bending hinge 0: stiffness nan must be >= 0"));
  EXPECT_THAT(messageAfter([](Scene& s) {
                s.bending_hinges[0].vertices = {0, 1, 2, 4};
              }),
              HasSubstr("bending hinge 0: degenerate rest triangle (1, 0, 4), area 0"));
  // Particle 3 sits above particle 0's side of edge 1-2: the hinge folds past 90 degrees.
  EXPECT_THAT(
      messageAfter([](Scene& s) {
        s.bending_hinges[0].vertices = {1, 2, 0, 3};
      }),
      HasSubstr("bending hinge 0: flipped rest hinge: triangles (1, 2, 0) and (2, 1, 3) are folded onto each other"));
}

TEST(SceneValidation, SurfaceTriangleIndicesAreInRange) {
  EXPECT_THAT(messageAfter([](Scene& s) {
                s.triangles.push_back({0, 4, 7});
              }),
              HasSubstr("triangle 1: index vertices[2] = 7 out of range [0, 5)"));
}

TEST(SceneValidation, PinRules) {
  EXPECT_THAT(messageAfter([](Scene& s) { s.pins[0].vertex = 5; }),
              HasSubstr("pin 0: index vertex = 5 out of range [0, 5)"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.pins[0].stiffness = -1.0; }),
              HasSubstr("pin 0: stiffness -1 must be >= 0"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.pins[0].target.position.x() = kNaN; }),
              HasSubstr("pin 0: target position (nan, 0, 0) is not finite"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.pins[0].target.velocity.z() = kInf; }),
              HasSubstr("pin 0: target velocity (0, 0, inf) is not finite"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.pins[0].target.amplitude.y() = kNaN; }),
              HasSubstr("pin 0: target amplitude (0, nan, 0) is not finite"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.pins[0].target.frequency = kInf; }),
              HasSubstr("pin 0: target frequency inf is not finite"));
}

TEST(SceneValidation, ForceFieldRules) {
  EXPECT_THAT(messageAfter([](Scene& s) { s.force_fields[0].particles[1] = 7; }),
              HasSubstr("force field 0: index particles[1] = 7 out of range [0, 5)"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.force_fields[0].force.x() = kNaN; }),
              HasSubstr("force field 0: force (nan, 0, 0) is not finite"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.force_fields[0].rate.x() = kInf; }),
              HasSubstr("force field 0: rate (inf, 0, 0) is not finite"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.force_fields[0].amplitude.z() = kNaN; }),
              HasSubstr("force field 0: amplitude (0, 0, nan) is not finite"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.force_fields[0].frequency = kNaN; }),
              HasSubstr("force field 0: frequency nan is not finite"));
}

TEST(SceneValidation, BodyRules) {
  EXPECT_THAT(messageAfter([](Scene& s) { s.bodies[0].damping = 1.5; }),
              HasSubstr("body 'cloth': damping 1.5 outside [0, 1]"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.bodies[0].damping = -0.1; }),
              HasSubstr("body 'cloth': damping -0.1 outside [0, 1]"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.bodies[0].damping = kNaN; }),
              HasSubstr("body 'cloth': damping nan outside [0, 1]"));
  EXPECT_THAT(messageAfter([](Scene& s) {
                s.bodies[0].name.clear();
                s.bodies[0].particles[0] = 12;
              }),
              HasSubstr("body 0: index particles[0] = 12 out of range [0, 5)"));
  EXPECT_THAT(messageAfter([](Scene& s) { s.bodies[0].particles[4] = 1; }),
              HasSubstr("body 'cloth': particle 1 listed twice"));
}

TEST(SceneValidation, AThrowLeavesTheCallersSceneUnchanged) {
  Scene s = validScene();
  s.springs[1].b = 99;
  const Scene before = s;
  EXPECT_THROW(validateScene(s), InvalidInputError);
  EXPECT_THROW(SceneData{s}, InvalidInputError);
  EXPECT_EQ(s.positions, before.positions);
  EXPECT_EQ(s.rest_positions, before.rest_positions);
  EXPECT_EQ(s.velocities, before.velocities);
  EXPECT_EQ(s.masses, before.masses);
  ASSERT_EQ(s.springs.size(), before.springs.size());
  EXPECT_EQ(s.springs[1].b, 99);
  EXPECT_EQ(s.tets.size(), before.tets.size());
  EXPECT_EQ(s.pins.size(), before.pins.size());
  EXPECT_EQ(s.bodies[0].particles, before.bodies[0].particles);
}

TEST(SceneValidation, IsAnErrorOfTheLibrary) {
  Scene s = validScene();
  s.masses[0] = 0.0;
  EXPECT_THROW(validateScene(s), Error);  // a program can catch stabint::Error alone
}

}  // namespace
}  // namespace stabint
