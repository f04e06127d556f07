// Energy bookkeeping of the tracked target H* (docs/method.md): damping lowers it by exactly the
// kinetic energy removed, time-dependent potentials move it by IM's work rule, and otherwise it
// stays constant. The simulator-level tests run on every backend (tests/backend_suite.hpp); the
// H* arithmetic is the host's in double on all of them, the energies it books are the backend's.
// Float tolerances: an energy evaluated in float is off by a few u = 2^-24 of the size of its
// terms (not of the total, which may cancel), so comparisons of energies use multiples of
// u times those sizes; each test says how many and what was measured on PoCL.
#include <stabint/stabint.hpp>

#include "backend_suite.hpp"
#include "integrator/damping.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>

namespace stabint {
namespace {

class Bookkeeping : public testing::BackendTest {};

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

// Exact on every backend: nothing is booked, so H* is never touched.
TEST_P(Bookkeeping, UndampedUnforcedSceneKeepsItsTargetConstant) {
  for (Integrator integrator : allIntegrators()) {
    SimulatorOptions o = options();
    o.integrator = integrator;
    // FE and SE gain energy by about (omega h)^2 per step in the cloth's stiffest mode (omega
    // about 1.5e4 rad/s): at h = 5e-5 they stay finite over the 30 steps, in float too.
    o.time_step =
        integrator == Integrator::ForwardEuler || integrator == Integrator::SymplecticEuler ? 5e-5 : 1.0 / 30.0;
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

// H* - damping is host arithmetic in double on every backend, hence the same tolerance.
TEST_P(Bookkeeping, DampingLowersTheTargetByExactlyTheKineticEnergyRemoved) {
  SimulatorOptions o = options();
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
TEST(DampingFunction, ReportsItsEnergyAndKeepsMomentum) {
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

// Time-dependent forcing: H* changes by the work rule implicit midpoint obeys (docs/method.md,
// "Forcing"): [U(x1, t1) - U(x1, tm)] + [U(x0, tm) - U(x0, t0)], tm = (t0 + t1)/2, with U the
// time-dependent potential (pins and force fields) computed here from the scene description,
// independently of the library's energy code. For the blend x1 is the IM candidate, which is the
// step's result on the steps that accept it or only scale its velocities; those are checked.
double forcedPotential(const Scene& s, const Eigen::MatrixX3d& x, double t) {
  double u = 0.0;
  for (const Pin& pin : s.pins)
    u += 0.5 * pin.stiffness * (x.row(pin.vertex).transpose() - pin.target.at(t)).squaredNorm();
  for (const ForceField& field : s.force_fields)
    for (int j : field.particles) u -= field.at(t).dot(x.row(j).transpose());
  return u;
}

double expectedForcing(const Scene& s, const Eigen::MatrixX3d& x0, const Eigen::MatrixX3d& x1, double t0, double t1) {
  const double tm = 0.5 * (t0 + t1);
  return (forcedPotential(s, x1, t1) - forcedPotential(s, x1, tm)) +
         (forcedPotential(s, x0, tm) - forcedPotential(s, x0, t0));
}

/// The scale of the float round-off of one evaluation of the pins + external potential at (x, t):
/// the sum of the magnitudes of its terms, where a pin's term 1/2 k |x - q|^2 counts with the
/// error k |x - q| (|x| + |q|) that rounding x and q to float before the difference gives it. The
/// forcing rule differences that whole potential, gravity included, so gravity's terms count
/// although they cancel in the difference.
double forcedTermSize(const Scene& s, const Eigen::MatrixX3d& x, double t) {
  double size = 0.0;
  for (const Pin& pin : s.pins) {
    const Eigen::Vector3d xj = x.row(pin.vertex).transpose(), q = pin.target.at(t);
    const double d = (xj - q).norm();
    size += pin.stiffness * (0.5 * d * d + d * (xj.norm() + q.norm()));
  }
  for (int j = 0; j < s.numParticles(); ++j) size += std::abs(s.masses[j] * s.gravity.dot(x.row(j).transpose()));
  for (const ForceField& field : s.force_fields)
    for (int j : field.particles) size += std::abs(field.at(t).dot(x.row(j).transpose()));
  return size;
}

/// The same for the rule's four evaluations.
double forcingTermSize(const Scene& s, const Eigen::MatrixX3d& x0, const Eigen::MatrixX3d& x1, double t0, double t1) {
  const double tm = 0.5 * (t0 + t1);
  return forcedTermSize(s, x1, t1) + forcedTermSize(s, x1, tm) + forcedTermSize(s, x0, tm) + forcedTermSize(s, x0, t0);
}

// Returns how many steps were checked. Tolerance of the forcing: double 1e-9 of its size, float
// 2 u of the round-off scale of the rule's four potentials (forcingTermSize; measured on PoCL:
// at most 0.13 u of it).
int checkForcing(const testing::BackendUnderTest& backend, const Scene& s, Integrator integrator, int steps) {
  SimulatorOptions o = backend.apply({});
  o.integrator = integrator;
  o.energy_tolerance = 0.5;
  Simulator sim(s, o);
  int checked = 0;
  for (int n = 0; n < steps; ++n) {
    const Eigen::MatrixX3d x0 = sim.positions();
    const double t0 = sim.time(), t1 = t0 + o.time_step, before = sim.target();
    const StepReport& r = sim.step();
    EXPECT_NE(r.forcing, 0.0) << "step " << n;
    EXPECT_NEAR(r.target, before + r.forcing - r.damping, 1e-12 * std::max(1.0, std::abs(before)));
    if (r.branch == BlendBranch::BackwardEuler) continue;
    const double expected = expectedForcing(s, x0, sim.positions(), t0, t1);
    const double tol = backend.isFloat()
                           ? 2.0 * backend.unitRoundoff() * forcingTermSize(s, x0, sim.positions(), t0, t1)
                           : 1e-9 * std::max(1.0, std::abs(expected));
    EXPECT_NEAR(r.forcing, expected, tol) << "step " << n;
    ++checked;
  }
  return checked;
}

// One particle on a sinusoidally moving pin, no gravity: the system is linear, so IM is exact in
// one local/global iteration and its energy changes by exactly the forcing rule's work. H* must
// equal IM's energy to round-off at every step, for soft and very stiff pins alike (the
// one-midpoint rule of the first version missed by 1.7, 12.7 and 1042 J for these stiffnesses).
// The blend then has nothing to correct. Float: H* sums 120 forcing terms, each off by the
// round-off of its four potentials (forcingTermSize), which dwarfs the energy itself for the
// stiff pins (terms of k |x - q| |x| that cancel); the tolerance is 2 u of their sum over the
// run (measured on PoCL: at most 0.18 u of it).
TEST_P(Bookkeeping, SinusoidalPinTargetEqualsImplicitMidpointEnergy) {
  for (double k : {1e2, 1e4, 1e6}) {
    Scene s;
    s.name = "particle on a moving pin";
    s.positions = Eigen::MatrixX3d::Zero(1, 3);
    s.rest_positions = s.positions;
    s.velocities = Eigen::MatrixX3d::Zero(1, 3);
    s.masses = Eigen::VectorXd::Constant(1, 0.1);
    s.gravity.setZero();
    Pin pin;
    pin.stiffness = k;
    pin.target.amplitude = Eigen::Vector3d(0.3, 0.1, 0.0);
    pin.target.frequency = 2.0;
    s.pins.push_back(pin);
    for (Integrator integrator : {Integrator::ImplicitMidpoint, Integrator::EnergyBlend}) {
      SimulatorOptions o = options();
      o.integrator = integrator;
      o.iterations = 1;
      Simulator sim(s, o);
      double max_dev = 0.0, max_energy = 0.0, booked_size = 0.0;
      for (int n = 0; n < 120; ++n) {
        const Eigen::MatrixX3d x0 = sim.positions();
        const double t0 = sim.time();
        const StepReport& r = sim.step();
        booked_size += forcingTermSize(s, x0, sim.positions(), t0, sim.time());
        max_dev = std::max(max_dev, std::abs(r.energy.total() - r.target));
        max_energy = std::max(max_energy, std::abs(r.energy.total()));
      }
      // Round-off of energies of size max_energy summed over 120 steps.
      const double tol =
          backend().isFloat() ? 2.0 * backend().unitRoundoff() * booked_size : 1e-10 * std::max(1.0, max_energy);
      EXPECT_LT(max_dev, tol) << "k = " << k << " " << integratorName(integrator);
    }
  }
}

TEST_P(Bookkeeping, MovingPinChangesTheTargetByThePotentialChange) {
  Scene s = smallCloth(0.0);
  s.pins[0].target.velocity = Eigen::Vector3d(0.2, 0.0, 0.1);
  s.pins[1].target.amplitude = Eigen::Vector3d(0.0, 0.0, 0.05);
  s.pins[1].target.frequency = 1.0;
  EXPECT_EQ(checkForcing(backend(), s, Integrator::BackwardEuler, 30), 30);
  EXPECT_EQ(checkForcing(backend(), s, Integrator::ImplicitMidpoint, 30), 30);
  EXPECT_GT(checkForcing(backend(), s, Integrator::EnergyBlend, 30), 20);
}

TEST_P(Bookkeeping, ChangingForceFieldChangesTheTargetByThePotentialChange) {
  Scene s = smallCloth(0.0);
  ForceField wind;
  wind.particles = {3, 10, 20, 40};
  wind.force = Eigen::Vector3d(0.0, 0.0, 0.01);
  wind.rate = Eigen::Vector3d(0.0, 0.0, 0.02);
  wind.amplitude = Eigen::Vector3d(0.01, 0.0, 0.0);
  wind.frequency = 2.0;
  s.force_fields.push_back(wind);
  EXPECT_EQ(checkForcing(backend(), s, Integrator::BDF2, 30), 30);
  EXPECT_GT(checkForcing(backend(), s, Integrator::EnergyBlend, 30), 20);
}

// A cloth dragged by a stiff handle along a steady path: the target must follow the physical
// work, not grow by k/2 |dq|^2 every step. After the start-up transient the handle pulls a cloth
// that moves with it, so the target stays within a few joules; the x_n rule of the starting spec grew
// it by ~55 J per step here. The thresholds are far above float's round-off.
TEST_P(Bookkeeping, StiffMovingHandleDoesNotPumpTheTarget) {
  Scene s = smallCloth(0.0);
  for (Pin& pin : s.pins) pin.target.velocity = Eigen::Vector3d(1.0, 0.0, 0.0);
  for (Pin& pin : s.pins) pin.stiffness = 1e5;
  SimulatorOptions o = options();
  o.integrator = Integrator::EnergyBlend;
  Simulator sim(s, o);
  const double h0 = sim.target();
  double max_forcing = 0.0;
  for (int n = 0; n < 60; ++n) max_forcing = std::max(max_forcing, std::abs(sim.step().forcing));
  const double k_half_dq2 = 0.5 * 1e5 * std::pow(o.time_step, 2.0);  // the bias per pin per step
  EXPECT_LT(max_forcing, 0.1 * k_half_dq2);
  EXPECT_LT(std::abs(sim.target() - h0), 5.0);
}

STABINT_ON_EVERY_BACKEND(Bookkeeping);

}  // namespace
}  // namespace stabint
