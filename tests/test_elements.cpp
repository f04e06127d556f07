// Element math of the CPU reference path against independent checks: rotations are proper and
// orthonormal, projections are idempotent and nearest, energies vanish at rest and are
// invariant under rigid motion, and the forces the backend computes are the negative
// finite-difference gradient of the energy it reports; for springs, tets and pins and for
// triangle strain and bending hinges.
#include <stabint/stabint.hpp>

#include "cpu/cpu_backend.hpp"
#include "elements/element_type.hpp"
#include "elements/projections.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"
#include "triangle_cloth_scene.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <Eigen/SVD>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>

namespace stabint {
namespace {

Eigen::Matrix3d randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n;
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

TEST(Elements, NearestRotationIsProperAndOrthonormalForAnyF) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int trial = 0; trial < 500; ++trial) {
    Eigen::Matrix3d F;
    for (int i = 0; i < 9; ++i) F(i) = u(rng);
    if (trial % 5 == 0) F.col(2) = 0.3 * F.col(0) - F.col(1);  // rank-deficient (flat tet)
    if (trial % 7 == 0) F.col(0) *= -1.0;                      // inverted
    const Eigen::Matrix3d R = projections::nearestRotation(F);
    EXPECT_NEAR((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12) << F;
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12) << F;
    // Nearest among proper rotations: no random rotation is closer.
    for (int k = 0; k < 20; ++k) EXPECT_LE((F - R).norm(), (F - randomRotation(rng)).norm() + 1e-12);
  }
}

TEST(Elements, NearestRotationRecoversTheRotationOfAStretch) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Matrix3d Q = randomRotation(rng);
    const Eigen::Matrix3d S = Eigen::Vector3d(1.5, 0.8, 0.3).asDiagonal();
    EXPECT_NEAR((projections::nearestRotation(Q * S) - Q).norm(), 0.0, 1e-12);
  }
}

// The fast rotation (Newton's polar iteration, an eigen-decomposition for inverted and flat F)
// against Eigen's two-sided Jacobi SVD, the method the tet used before, over the deformations a
// simulation meets: small to large stretches, nearly flat and inverted elements. Where the
// nearest rotation is unique (singular values of F, the smallest one signed by det F, with
// s2 + s3 clear of 0) both must agree to round-off amplified by the condition number of the polar
// factor, 1/(s2 + s3): 1e-13 over that bound leaves a factor 20 to the ~5e-15 measured.
TEST(Elements, NearestRotationMatchesTheSvdOracle) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 4000; ++trial) {
    // Singular values from a 1 % stretch to a 10:1 one, one of them down to 1e-7 (flat) in
    // some trials, the smallest negated (inverted) in others.
    const double spread = trial % 4 == 0 ? 0.01 : trial % 4 == 1 ? 0.2 : trial % 4 == 2 ? 1.0 : 3.0;
    Eigen::Vector3d s;
    for (int i = 0; i < 3; ++i) s[i] = std::exp(spread * (u(rng) - 0.5));
    if (trial % 5 == 0) s[2] = std::pow(10.0, -7.0 * u(rng));
    std::sort(s.data(), s.data() + 3, std::greater<double>());
    if (trial % 3 == 0) s[2] = -s[2];
    const Eigen::Matrix3d U = randomRotation(rng), V = randomRotation(rng);
    const double scale = std::exp(n(rng));  // the result does not depend on the size of F
    const Eigen::Matrix3d F = scale * U * s.asDiagonal() * V.transpose();
    const Eigen::Matrix3d R = projections::nearestRotation(F);
    const Eigen::Matrix3d expected = U * V.transpose();
    EXPECT_NEAR((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-13) << F;
    EXPECT_NEAR(R.determinant(), 1.0, 1e-13) << F;
    const double conditioning = 1.0 / (s[1] + s[2]);
    if (s[1] + s[2] < 1e-3) continue;  // nearly a tie between two rotations: either is nearest
    EXPECT_NEAR((R - expected).norm(), 0.0, 1e-13 * conditioning) << "singular values " << s.transpose();
    EXPECT_NEAR((R - projections::nearestRotationBySvd(F)).norm(), 0.0, 1e-13 * conditioning)
        << "singular values " << s.transpose();
    // The same rotation whichever way the 9 reals are read (the tet passes F^T as stored).
    const Eigen::Matrix3d Ft = F.transpose();
    EXPECT_NEAR((projections::nearestRotation(Ft) - R.transpose()).norm(), 0.0, 1e-13 * conditioning);
  }
}

// The CPU reference's passes take rotations kLanes at a time. Each lane must be the one-at-a-time
// rotation bit for bit, whatever its neighbours do: groups mixing near-rotations (few Newton
// iterations), large stretches (many), inverted and flat matrices (the eigen-decomposition) and
// a zero matrix, so that lanes settle, go on and are refused in the same call.
TEST(Elements, RotationsOfAGroupAreEachLanesOwnBitForBit) {
  constexpr int W = projections::kLanes;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int group = 0; group < 400; ++group) {
    double m[9][W], r[9][W];
    std::array<Eigen::Matrix3d, W> f;
    for (int l = 0; l < W; ++l) {
      const int kind = (group + 3 * l) % 6;
      Eigen::Matrix3d F = randomRotation(rng);
      if (kind == 1) F += 1e-3 * Eigen::Matrix3d::Random();
      if (kind == 2) F = F * Eigen::Vector3d(4.0, 0.7, 0.05).asDiagonal();
      if (kind == 3) F.col(0) *= -1.0;                      // inverted
      if (kind == 4) F.col(2) = 0.5 * F.col(0) + F.col(1);  // flat
      if (kind == 5 && group % 7 == 0) F.setZero();
      for (int i = 0; i < 9; ++i) F(i) += kind == 0 ? 0.3 * u(rng) : 0.0;
      f[std::size_t(l)] = F;
      for (int i = 0; i < 9; ++i) m[i][l] = F(i);
    }
    projections::nearestRotations(m, r);
    for (int l = 0; l < W; ++l) {
      const Eigen::Matrix3d one = projections::nearestRotation(f[std::size_t(l)]);
      for (int i = 0; i < 9; ++i)
        ASSERT_EQ(r[i][l], one(i)) << "group " << group << " lane " << l << "\n" << f[std::size_t(l)];
    }
  }
}

TEST(Elements, SphereProjectionHasTheRadiusAndADefinedDegenerateCase) {
  const Eigen::Vector3d d(0.3, -0.4, 1.2);
  const double params_x[5] = {10.0, 0.7, 1.0, 0.0, 0.0}, params_y[5] = {10.0, 0.7, 0.0, 1.0, 0.0};
  Eigen::Vector3d p;
  const double energy = projections::ontoSphere(d.data(), params_x, p.data());
  EXPECT_NEAR(p.norm(), 0.7, 1e-15);
  EXPECT_NEAR(p.normalized().dot(d.normalized()), 1.0, 1e-15);
  EXPECT_NEAR(energy, 5.0 * (d.norm() - 0.7) * (d.norm() - 0.7), 1e-15);
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  EXPECT_NEAR(projections::ontoSphere(zero.data(), params_y, p.data()), 5.0 * 0.49, 1e-15);
  EXPECT_EQ(p, Eigen::Vector3d(0.0, 0.7, 0.0));
}

// A scene with springs, tets, pins (one moving), gravity and a time-dependent force field.
Scene mixedScene() {
  TetBarParams bar;
  bar.nx = 3;
  bar.ny = 1;
  bar.nz = 1;
  Scene s = makeTetBar(bar);
  s.springs.push_back({0, s.numParticles() - 1, 0.9, 300.0});
  s.springs.push_back({2, 5, 0.1, 150.0});
  s.pins[0].target.velocity = Eigen::Vector3d(0.1, 0.2, 0.0);
  s.pins[0].target.amplitude = Eigen::Vector3d(0.0, 0.0, 0.05);
  s.pins[0].target.frequency = 2.0;
  ForceField wind;
  wind.force = Eigen::Vector3d(0.5, 0.0, 0.1);
  wind.amplitude = Eigen::Vector3d(0.0, 0.3, 0.0);
  wind.frequency = 1.5;
  s.force_fields.push_back(wind);
  return s;
}

Eigen::MatrixX3d perturbed(const Eigen::MatrixX3d& x, double scale, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, scale);
  Eigen::MatrixX3d out = x;
  for (Eigen::Index i = 0; i < out.size(); ++i) out(i) += n(rng);
  return out;
}

// The scenes the energy and force checks run on: springs, tets and pins with time-dependent
// forcing; and triangle strain with bending hinges on a curved rest shape.
Scene forcesScene(bool triangles) {
  if (!triangles) return mixedScene();
  Scene s = testing::triangleCloth();
  s.pins[0].target.velocity = Eigen::Vector3d(0.0, 0.1, 0.2);
  ForceField wind;
  wind.force = Eigen::Vector3d(0.0, 0.0, 0.02);
  wind.rate = Eigen::Vector3d(0.01, 0.0, 0.0);
  s.force_fields.push_back(wind);
  return s;
}

class ElementEnergyTest : public ::testing::TestWithParam<bool> {};

TEST_P(ElementEnergyTest, EnergyIsZeroAtRestAndInvariantUnderRigidMotion) {
  Scene s = forcesScene(GetParam());
  if (!GetParam()) s.springs.clear();  // mixedScene's extra springs are not at rest
  s.pins.clear();                      // pins are not rigid-invariant
  s.gravity.setZero();
  s.force_fields.clear();
  SceneData data(s);
  Forcing forcing(data.scene());
  auto backend = makeCpuBackend(data, forcing, 1);
  backend->write(0, s.rest_positions);
  // At rest each projection returns A x itself up to round-off (1e-16 relative), whose square
  // is far below 1e-20 of the deformed energy below.
  const double at_rest = backend->potential(0, 0.0).total();

  const Eigen::MatrixX3d deformed = perturbed(s.rest_positions, 0.02, 1);
  backend->write(0, deformed);
  const double e = backend->potential(0, 0.0).internal;
  EXPECT_GT(e, 0.0);
  EXPECT_LT(std::abs(at_rest), 1e-20 * e);
  std::mt19937 rng(5);
  const Eigen::Matrix3d Q = randomRotation(rng);
  Eigen::MatrixX3d moved = (deformed * Q.transpose()).rowwise() + Eigen::RowVector3d(1.0, -2.0, 0.5);
  backend->write(0, moved);
  EXPECT_NEAR(backend->potential(0, 0.0).internal, e, 1e-10 * e);
}

// f = -grad (E_int + U_ext): compare M a with a central finite difference of the energy.
TEST_P(ElementEnergyTest, ForcesAreTheNegativeEnergyGradient) {
  const Scene s = forcesScene(GetParam());
  SceneData data(s);
  Forcing forcing(data.scene());
  auto backend = makeCpuBackend(data, forcing, 2);
  const double t = 0.37;
  const Eigen::MatrixX3d x = perturbed(s.rest_positions, 0.05, 2);
  backend->write(0, x);
  backend->accelerations(1, 0, t);
  Eigen::MatrixX3d a;
  backend->read(1, a);
  const Eigen::MatrixX3d force = a.array().colwise() * s.masses.array();

  const double eps = 1e-6;
  double max_error = 0.0, max_force = 0.0;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    Eigen::MatrixX3d xp = x, xm = x;
    xp(i) += eps;
    xm(i) -= eps;
    backend->write(0, xp);
    const double ep = backend->potential(0, t).total();
    backend->write(0, xm);
    const double em = backend->potential(0, t).total();
    const double fd = -(ep - em) / (2.0 * eps);
    max_error = std::max(max_error, std::abs(fd - force(i)));
    max_force = std::max(max_force, std::abs(force(i)));
  }
  // Central differences: truncation O(eps^2 E''') plus round-off O(E/eps * 1e-16); with the
  // energies and stiffnesses here both are below 1e-6 of the largest force. (The strain limits
  // make the triangle energy's second derivative jump where a singular value crosses a limit;
  // with this perturbation no singular value lies within eps of one.)
  EXPECT_LT(max_error, 1e-6 * max_force) << "max force " << max_force;
}

INSTANTIATE_TEST_SUITE_P(Scenes, ElementEnergyTest, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "TrianglesAndHinges" : "SpringsTetsPins"; });

size_t typeIndex(const std::string& name) {
  for (size_t i = 0; i < elementTypes().size(); ++i)
    if (name == elementTypes()[i]->name()) return i;
  throw std::runtime_error("no element type " + name);
}

Eigen::Vector2d singularValues(const Eigen::Matrix<double, 3, 2>& m) {
  return Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>>(m).singularValues();
}

// Triangle strain: P has its singular values in [s_min, s_max], projecting it again changes
// nothing, and no other matrix with singular values in the range is closer to F.
TEST(Elements, TriangleStrainProjectionIsIdempotentAndNearestWithinTheLimits) {
  const ElementType& type = *elementTypes()[typeIndex("triangle strain")];
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (const auto& limits : {std::array<double, 2>{1.0, 1.0}, std::array<double, 2>{0.8, 1.1}}) {
    const double params[3] = {2.0, limits[0], limits[1]};
    std::uniform_real_distribution<double> in_range(limits[0], limits[1]);
    for (int trial = 0; trial < 300; ++trial) {
      Eigen::Matrix<double, 3, 2> F;
      for (int i = 0; i < 6; ++i) F(i) = u(rng);
      if (trial % 10 == 0) F.col(1) = 0.5 * F.col(0);  // rank 1: a collapsed triangle
      Eigen::Matrix<double, 3, 2> P, PP;
      // ax is F^T row-major, i.e. F column-major: the same memory.
      const double energy = type.project(F.data(), params, P.data());
      EXPECT_NEAR(energy, 0.5 * params[0] * (F - P).squaredNorm(), 1e-12);
      const Eigen::Vector2d s = singularValues(P);
      EXPECT_GE(s.minCoeff(), limits[0] - 1e-12) << F;
      EXPECT_LE(s.maxCoeff(), limits[1] + 1e-12) << F;
      EXPECT_NEAR(type.project(P.data(), params, PP.data()), 0.0, 1e-24);
      EXPECT_LT((PP - P).norm(), 1e-12) << F;
      for (int k = 0; k < 20; ++k) {
        // A random member of the set: orthonormal columns scaled by values in the range.
        const Eigen::Matrix3d Q = randomRotation(rng);
        const Eigen::Matrix2d V = Eigen::Rotation2Dd(u(rng)).toRotationMatrix();
        const Eigen::Matrix<double, 3, 2> candidate =
            Q.leftCols<2>() * Eigen::Vector2d(in_range(rng), in_range(rng)).asDiagonal() * V.transpose();
        EXPECT_LE((F - P).norm(), (F - candidate).norm() + 1e-12);
      }
    }
  }
}

// Triangle strain against Eigen's Jacobi SVD of F (3 by 2): P = U clamp(S) V^T to round-off
// wherever P is unique (s1 clear of s2), down to nearly collapsed triangles; with no lower limit
// the small singular value survives unclamped and must keep its digits (a square root of an
// eigenvalue of F^T F would lose half of them: 1e-8 absolute). 1e-13 is a factor 20 over the
// ~5e-15 measured for these O(1) matrices.
TEST(Elements, TriangleStrainProjectionMatchesTheSvdOracle) {
  const ElementType& type = *elementTypes()[typeIndex("triangle strain")];
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const auto& limits :
       {std::array<double, 2>{1.0, 1.0}, std::array<double, 2>{0.0, 1.05}, std::array<double, 2>{0.9, 2.0}}) {
    const double params[3] = {1.0, limits[0], limits[1]};
    for (int trial = 0; trial < 1000; ++trial) {
      double s1 = 0.5 + u(rng), s2 = 0.5 + u(rng);
      if (s1 < s2) std::swap(s1, s2);
      if (trial % 4 == 0) s2 = s1 * std::pow(10.0, -10.0 * u(rng));  // nearly collapsed
      if (s1 - s2 < 1e-3 * s1) continue;                             // nearly equal: V is not unique (P is, but not V)
      const Eigen::Matrix3d Q = randomRotation(rng);
      const Eigen::Matrix2d V = Eigen::Rotation2Dd(6.283185307179586 * u(rng)).toRotationMatrix();
      const Eigen::Matrix<double, 3, 2> F = Q.leftCols<2>() * Eigen::Vector2d(s1, s2).asDiagonal() * V.transpose();
      Eigen::Matrix<double, 3, 2> P;
      type.project(F.data(), params, P.data());
      Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>> svd(F, Eigen::ComputeThinU | Eigen::ComputeThinV);
      const Eigen::Vector2d clamped = svd.singularValues().cwiseMax(limits[0]).cwiseMin(limits[1]);
      const Eigen::Matrix<double, 3, 2> expected = svd.matrixU() * clamped.asDiagonal() * svd.matrixV().transpose();
      // A clamped s2 keeps the direction u2 of F v2, which rounding F by epsilon s1 turns by
      // epsilon s1/s2 for every method (the oracle too): the tolerance grows with that.
      const bool s2_clamped = s2 < limits[0] || s2 > limits[1];
      const double tolerance = 1e-13 + (s2_clamped ? 1e-14 * s1 / s2 : 0.0);
      EXPECT_NEAR((P - expected).norm(), 0.0, tolerance) << "s = " << s1 << ", " << s2;
    }
  }
}

// Bending hinge: p has the rest length and the direction of A x; projecting again changes nothing.
TEST(Elements, BendingHingeProjectionKeepsTheRestCurvatureMagnitude) {
  const ElementType& type = *elementTypes()[typeIndex("bending hinge")];
  const double params[5] = {3.0, 0.4, 0.0, 0.0, 1.0};
  const Eigen::Vector3d v(0.3, -0.2, 0.9);
  Eigen::Vector3d p, pp;
  EXPECT_NEAR(type.project(v.data(), params, p.data()), 1.5 * (v.norm() - 0.4) * (v.norm() - 0.4), 1e-15);
  EXPECT_NEAR(p.norm(), 0.4, 1e-15);
  EXPECT_NEAR(p.normalized().dot(v.normalized()), 1.0, 1e-15);
  EXPECT_NEAR(type.project(p.data(), params, pp.data()), 0.0, 1e-30);
  EXPECT_LT((pp - p).norm(), 1e-15);
}

// The hinge weights K of a flat hinge whose four edge angles are 45 degrees (cot = 1):
// K = [c1 + c3, c0 + c2, -(c0 + c1), -(c2 + c3)] = [2, 2, -2, -2], summing to zero
// (translations), with K x = 0 for the flat rest; w = 3 k / (A_0 + A_1) with both areas 1/4.
TEST(Elements, BendingHingeCoefficientsAreTheCotangentLaplacian) {
  Scene s;
  s.rest_positions.resize(4, 3);
  s.rest_positions << 0, 0, 0, 1, 0, 0, 0.5, 0.5, 0, 0.5, -0.5, 0;
  s.positions = s.rest_positions;
  s.velocities = Eigen::MatrixX3d::Zero(4, 3);
  s.masses = Eigen::VectorXd::Ones(4);
  s.bending_hinges.push_back(BendingHinge{{0, 1, 2, 3}, 1.0});
  const SceneData data(s);
  const ElementBlock& block = data.blocks()[typeIndex("bending hinge")];
  ASSERT_EQ(block.count, 1);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(block.coefficients[k], k < 2 ? 2.0 : -2.0, 1e-15);
  EXPECT_NEAR(block.params[0], 6.0, 1e-15);
  EXPECT_EQ(block.params[1], 0.0);
}

}  // namespace
}  // namespace stabint
