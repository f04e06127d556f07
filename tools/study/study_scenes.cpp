// The study's scenes and their energy scale.
#include "study.hpp"

#include <cmath>
#include <sstream>

namespace study {

namespace {

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

}  // namespace

StudyScene chainScene(double stiffness) {
  stabint::ChainPendulumParams p;
  p.stiffness = stiffness;
  StudyScene s;
  s.key = "chain";
  s.scene = stabint::makeChainPendulum(p);
  s.params = "chain particles=" + std::to_string(p.particles) + " mass=" + fmt(p.total_mass) +
             " length=" + fmt(p.length) + " k=" + fmt(p.stiffness) + " pin=" + fmt(p.pin_stiffness) +
             " g=" + fmt(p.gravity);
  return s;
}

// makeClothGrid hangs the cloth in the x-y plane with gravity in that plane: released at rest it
// only stretches in-plane and never leaves z = 0, so there are no folds for BE and BDF2 to smooth
// away (method.md section 5). Tilting it about its pinned top edge to 30 degrees below the
// horizontal makes it fall, swing and fold, and keeps a non-zero vertical extent so the
// simulator's E_scale (m g times the height along gravity) is not zero.
StudyScene clothScene() {
  stabint::ClothGridParams p;
  p.nx = 20;
  p.ny = 20;
  const double tilt = 30.0 * M_PI / 180.0;
  StudyScene s;
  s.key = "cloth";
  s.grid_nx = p.nx;
  s.grid_ny = p.ny;
  s.scene = stabint::makeClothGrid(p);
  Scene& sc = s.scene;
  for (int r = 0; r < sc.numParticles(); ++r) {
    const double x = sc.positions(r, 0);
    const double along = p.height - sc.positions(r, 1);  // distance from the pinned top edge
    sc.positions.row(r) << x, -along * std::sin(tilt), along * std::cos(tilt);
  }
  sc.rest_positions = sc.positions;  // springs keep their rest lengths: a rigid rotation
  // The energy function does not depend on the tilt (pins lie on the rotation axis), so the
  // equilibrium is the untilted cloth hanging straight down from the same edge.
  s.equilibrium_start = sc.positions;
  for (int r = 0; r < sc.numParticles(); ++r) {
    const double along = std::hypot(sc.positions(r, 1), sc.positions(r, 2));
    s.equilibrium_start.row(r) << sc.positions(r, 0), -along, 0.0;
  }
  for (stabint::Pin& pin : sc.pins) pin.target.position = sc.positions.row(pin.vertex).transpose();
  stabint::validateScene(sc);
  s.params = "cloth nx=20 ny=20 w=" + fmt(p.width) + " h=" + fmt(p.height) + " rho=" + fmt(p.areal_density) +
             " ks=" + fmt(p.stretch_stiffness) + " kshear=" + fmt(p.shear_stiffness) + " kb=" +
             fmt(p.bend_stiffness) + " pin=" + fmt(p.pin_stiffness) + " tilt=30deg";
  return s;
}

StudyScene tetBarScene(double stiffness) {
  stabint::TetBarParams p;
  p.nx = 8;
  p.ny = 2;
  p.nz = 2;
  p.stiffness = stiffness;
  StudyScene s;
  s.key = "tetbar";
  s.scene = stabint::makeTetBar(p);
  s.params = "tetbar nx=8 ny=2 nz=2 L=" + fmt(p.length) + " w=" + fmt(p.width) + " rho=" + fmt(p.density) +
             " k=" + fmt(p.stiffness) + " pin=" + fmt(p.pin_stiffness);
  // Particle (i, j, k) is i + px (j + py k) (builders.cpp); the free end is i = nx.
  const int px = p.nx + 1, py = p.ny + 1, pz = p.nz + 1;
  s.free_end_first = p.nx;
  s.free_end_stride = px;
  s.free_end_count = py * pz;
  return s;
}

double equilibriumPotential(const Scene& original, const Eigen::MatrixX3d& start) {
  Scene scene = original;
  if (start.rows() == scene.numParticles()) scene.positions = start;
  stabint::SimulatorOptions o;
  o.integrator = Integrator::BackwardEuler;
  o.time_step = 10.0;  // c = 1/h^2 = 0.01: each converged step is nearly a pure potential descent
  o.tolerance = 1e-11;
  o.max_iterations = 5000;
  stabint::Simulator sim(scene, o);
  double previous = sim.energy().elastic + sim.energy().external;
  for (int step = 0; step < 400; ++step) {
    sim.step();
    const double now = sim.energy().elastic + sim.energy().external;
    if (std::abs(previous - now) <= 1e-12 * std::max(1.0, std::abs(now))) break;
    previous = now;
  }
  return sim.energy().elastic + sim.energy().external;
}

double availableEnergy(const StudyScene& scene) {
  stabint::SimulatorOptions o;
  o.integrator = Integrator::BackwardEuler;
  stabint::Simulator sim(scene.scene, o);
  return sim.energy().total() - equilibriumPotential(scene.scene, scene.equilibrium_start);
}

}  // namespace study
