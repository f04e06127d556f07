// Energy bookkeeping of the tracked target H* (method.md section 3, steps 1 and 6): damping
// lowers it by exactly the kinetic energy removed, time-dependent potentials move it by their
// change at fixed positions, and otherwise it stays constant.
#include <stabint/stabint.hpp>

#include "integrator/damping.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>

namespace stabint {
namespace {

double kinetic(const Scene& s, const Eigen::MatrixX3d& v) {
  return 0.5 * (v.rowwise().squaredNorm().array() * s.masses.array()).sum();
}

Scene smallCloth(double damping) {
  ClothGridParams p;
  p.nx = 8;
  p.ny = 8;
  p.damping = damping;
  return makeClothGrid(p);
}

TEST(Bookkeeping, UndampedUnforcedSceneKeepsItsTargetConstant) {
  for (Integrator integrator : allIntegrators()) {
    SimulatorOptions o;
    o.integrator = integrator;
    o.time_step = integrator == Integrator::ForwardEuler || integrator == Integrator::SymplecticEuler ? 1e-3 : 1.0 / 30.0;
    Simulator sim(smallCloth(0.0), o);
    const double h0 = sim.energy().total();
    EXPECT_EQ(sim.target(), h0);
    for (int n = 0; n < 30; ++n) {
      const StepReport& r = sim.step();
      ASSERT_EQ(r.target, h0) << integratorName(integrator) << " step " << n;
      ASSERT_EQ(r.forcing, 0.0);
      ASSERT_EQ(r.damping, 0.0);
    }
  }
}

TEST(Bookkeeping, DampingLowersTheTargetByExactlyTheKineticEnergyRemoved) {
  SimulatorOptions o;
  o.integrator = Integrator::EnergyBlend;
  Scene s = smallCloth(0.2);
  s.velocities.col(2).setConstant(0.5);  // some motion to damp from the start
  for (Eigen::Index j = 0; j < s.velocities.rows(); ++j) s.velocities(j, 0) = 0.3 * s.positions(j, 1);
  Simulator sim(s, o);
  double target = sim.target();
  for (int n = 0; n < 40; ++n) {
    const StepReport& r = sim.step();
    ASSERT_GT(r.damping, 0.0) << "step " << n;
    ASSERT_NEAR(r.target, target - r.damping, 1e-12 * std::abs(target)) << "step " << n;
    target = r.target;
  }
}

// The damping function itself: the energy it reports equals the kinetic energy difference, and
// linear and angular momentum are preserved.
TEST(Bookkeeping, MomentumPreservingDampingReportsItsEnergyAndKeepsMomentum) {
  const Scene s = smallCloth(0.35);
  Eigen::MatrixX3d v = Eigen::MatrixX3d::Random(s.numParticles(), 3);
  const Eigen::MatrixX3d before = v;
  const double removed = applyMomentumPreservingDamping(s.bodies, s.masses, s.positions, v);
  EXPECT_NEAR(removed, kinetic(s, before) - kinetic(s, v), 1e-14);
  EXPECT_GT(removed, 0.0);
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero(), p1 = Eigen::Vector3d::Zero();
  Eigen::Vector3d l0 = Eigen::Vector3d::Zero(), l1 = Eigen::Vector3d::Zero();
  for (int j = 0; j < s.numParticles(); ++j) {
    const Eigen::Vector3d x = s.positions.row(j).transpose();
    p0 += s.masses[j] * before.row(j).transpose();
    p1 += s.masses[j] * v.row(j).transpose();
    l0 += s.masses[j] * x.cross(before.row(j).transpose());
    l1 += s.masses[j] * x.cross(v.row(j).transpose());
  }
  EXPECT_NEAR((p0 - p1).norm(), 0.0, 1e-14);
  EXPECT_NEAR((l0 - l1).norm(), 0.0, 1e-14);
  // A rigid motion is not damped at all.
  Eigen::MatrixX3d rigid(s.numParticles(), 3);
  const Eigen::Vector3d omega(0.1, -0.4, 0.3), vel(1.0, 2.0, -0.5);
  for (int j = 0; j < s.numParticles(); ++j)
    rigid.row(j) = (vel + omega.cross(Eigen::Vector3d(s.positions.row(j).transpose()))).transpose();
  const Eigen::MatrixX3d rigid_before = rigid;
  EXPECT_NEAR(applyMomentumPreservingDamping(s.bodies, s.masses, s.positions, rigid), 0.0, 1e-13);
  EXPECT_NEAR((rigid - rigid_before).norm(), 0.0, 1e-12);
}

// Moving pin: H* changes by sum_pins k/2 (|x_n - q(t_{n+1})|^2 - |x_n - q(t_n)|^2), computed here
// from the scene description, independently of the library's energy code.
TEST(Bookkeeping, MovingPinChangesTheTargetByThePotentialChange) {
  Scene s = smallCloth(0.0);
  s.pins[0].target.velocity = Eigen::Vector3d(0.2, 0.0, 0.1);
  s.pins[1].target.amplitude = Eigen::Vector3d(0.0, 0.0, 0.05);
  s.pins[1].target.frequency = 1.0;
  SimulatorOptions o;
  o.integrator = Integrator::EnergyBlend;
  Simulator sim(s, o);
  for (int n = 0; n < 30; ++n) {
    const Eigen::MatrixX3d x = sim.positions();
    const double t0 = sim.time(), t1 = t0 + o.time_step, before = sim.target();
    double expected = 0.0;
    for (const Pin& pin : s.pins) {
      const Eigen::Vector3d xj = x.row(pin.vertex).transpose();
      expected += 0.5 * pin.stiffness * ((xj - pin.target.at(t1)).squaredNorm() - (xj - pin.target.at(t0)).squaredNorm());
    }
    const StepReport& r = sim.step();
    ASSERT_NEAR(r.forcing, expected, 1e-9 * std::max(1.0, std::abs(expected))) << "step " << n;
    ASSERT_NEAR(r.target, before + expected, 1e-9 * std::max(1.0, std::abs(before))) << "step " << n;
  }
}

// Changing force field: H* changes by -(f(t_{n+1}) - f(t_n)) . x_n summed over the field's particles.
TEST(Bookkeeping, ChangingForceFieldChangesTheTargetByThePotentialChange) {
  Scene s = smallCloth(0.0);
  ForceField wind;
  wind.particles = {3, 10, 20, 40};
  wind.force = Eigen::Vector3d(0.0, 0.0, 0.01);
  wind.rate = Eigen::Vector3d(0.0, 0.0, 0.02);
  wind.amplitude = Eigen::Vector3d(0.01, 0.0, 0.0);
  wind.frequency = 2.0;
  s.force_fields.push_back(wind);
  SimulatorOptions o;
  Simulator sim(s, o);
  for (int n = 0; n < 30; ++n) {
    const Eigen::MatrixX3d x = sim.positions();
    const double t0 = sim.time(), t1 = t0 + o.time_step, before = sim.target();
    double expected = 0.0;
    for (int j : wind.particles) expected -= (wind.at(t1) - wind.at(t0)).dot(x.row(j).transpose());
    const StepReport& r = sim.step();
    ASSERT_NEAR(r.forcing, expected, 1e-12) << "step " << n;
    ASSERT_NEAR(r.target, before + expected, 1e-12 * std::max(1.0, std::abs(before))) << "step " << n;
  }
}

}  // namespace
}  // namespace stabint
