// Element math of the CPU reference path against independent checks: rotations are proper and
// orthonormal, energies vanish at rest and are invariant under rigid motion, and the forces the
// backend computes are the negative finite-difference gradient of the energy it reports.
#include <stabint/stabint.hpp>

#include "cpu/cpu_backend.hpp"
#include "elements/projections.hpp"
#include "scene/scene_data.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <random>

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
    for (int k = 0; k < 20; ++k)
      EXPECT_LE((F - R).norm(), (F - randomRotation(rng)).norm() + 1e-12);
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

TEST(Elements, SphereProjectionHasTheRadiusAndADefinedDegenerateCase) {
  const Eigen::Vector3d d(0.3, -0.4, 1.2);
  const Eigen::Vector3d unit_x = Eigen::Vector3d::UnitX(), unit_y = Eigen::Vector3d::UnitY();
  Eigen::Vector3d p;
  projections::ontoSphere(d.data(), 0.7, unit_x.data(), p.data());
  EXPECT_NEAR(p.norm(), 0.7, 1e-15);
  EXPECT_NEAR(p.normalized().dot(d.normalized()), 1.0, 1e-15);
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  projections::ontoSphere(zero.data(), 0.7, unit_y.data(), p.data());
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

TEST(Elements, EnergyIsZeroAtRestAndInvariantUnderRigidMotion) {
  Scene s = mixedScene();
  s.springs.clear();  // the extra springs above are not at rest
  s.pins.clear();     // pins are not rigid-invariant
  s.gravity.setZero();
  s.force_fields.clear();
  SceneData data(s);
  auto backend = makeCpuBackend(data, 1);
  backend->write(0, s.rest_positions);
  EXPECT_NEAR(backend->potential(0, 0.0).total(), 0.0, 1e-12);

  const Eigen::MatrixX3d deformed = perturbed(s.rest_positions, 0.02, 1);
  backend->write(0, deformed);
  const double e = backend->potential(0, 0.0).internal;
  EXPECT_GT(e, 0.0);
  std::mt19937 rng(5);
  const Eigen::Matrix3d Q = randomRotation(rng);
  Eigen::MatrixX3d moved = (deformed * Q.transpose()).rowwise() + Eigen::RowVector3d(1.0, -2.0, 0.5);
  backend->write(0, moved);
  EXPECT_NEAR(backend->potential(0, 0.0).internal, e, 1e-10 * e);
}

// f = -grad (E_int + U_ext): compare M a with a central finite difference of the energy.
TEST(Elements, ForcesAreTheNegativeEnergyGradient) {
  const Scene s = mixedScene();
  SceneData data(s);
  auto backend = makeCpuBackend(data, 2);
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
  // energies and stiffnesses here both are below 1e-6 of the largest force.
  EXPECT_LT(max_error, 1e-6 * max_force) << "max force " << max_force;
}

}  // namespace
}  // namespace stabint
