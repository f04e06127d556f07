// The study's scenes and their energy scale.
#include "cache.hpp"
#include "study.hpp"

#include <cmath>
#include <sstream>

#ifndef STABINT_STUDY_SCENES_DIR
#define STABINT_STUDY_SCENES_DIR "scenes"
#endif

namespace study {

namespace {

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// A hash of every number of a scene loaded from a file: the cache key of its reference changes
// whenever the file (or the mesh it names) does. Its colliders go into the key through
// cacheDescription(), as every scene's do.
std::string fingerprint(const Scene& sc) {
  std::ostringstream t;
  t.precision(17);
  auto put = [&t](const auto& matrix) {
    for (Eigen::Index i = 0; i < matrix.size(); ++i) t << matrix.data()[i] << ' ';
  };
  put(sc.positions);
  put(sc.rest_positions);
  put(sc.velocities);
  put(sc.masses);
  put(sc.gravity);
  for (const stabint::Spring& e : sc.springs)
    t << e.a << ' ' << e.b << ' ' << e.rest_length << ' ' << e.stiffness << ' ';
  for (const stabint::Tet& e : sc.tets) {
    for (int v : e.vertices) t << v << ' ';
    t << e.stiffness << ' ';
  }
  for (const stabint::Pin& p : sc.pins) {
    t << p.vertex << ' ' << p.stiffness << ' ' << p.target.frequency << ' ';
    put(p.target.position);
    put(p.target.velocity);
    put(p.target.amplitude);
  }
  for (const stabint::ForceField& f : sc.force_fields) {
    for (int v : f.particles) t << v << ' ';
    t << f.frequency << ' ';
    put(f.force);
    put(f.rate);
    put(f.amplitude);
  }
  for (const stabint::Body& b : sc.bodies) {
    for (int v : b.particles) t << v << ' ';
    t << b.damping << ' ';
  }
  std::ostringstream hex;
  hex << std::hex << fnv1a(t.str());
  return hex.str();
}

}  // namespace

StudyScene chainScene(double stiffness) {
  stabint::ChainPendulumParams p;
  p.stiffness = stiffness;
  StudyScene s;
  s.key = "chain";
  // SE's energy error is first order in h and peaks when the chain whips around its pin:
  // max |H - H0| over 10 s is 1.9e-3, 8.6e-4, 3.1e-4 J at h/2000, h/4000, h/8000 (E_avail
  // 0.49 J); h/32000 keeps it below 3e-4 E_avail. A step costs 0.6 us here.
  s.reference_substeps = 32000;
  s.scene = stabint::makeChainPendulum(p);
  s.params = "chain particles=" + std::to_string(p.particles) + " mass=" + fmt(p.total_mass) +
             " length=" + fmt(p.length) + " k=" + fmt(p.stiffness) + " pin=" + fmt(p.pin_stiffness) +
             " g=" + fmt(p.gravity);
  return s;
}

// makeClothGrid hangs the cloth in the x-y plane with gravity in that plane: released at rest it
// only stretches in-plane and never leaves z = 0, so there are no folds for BE and BDF2 to smooth
// away (docs/method.md section 9). Tilting it about its pinned top edge to 30 degrees below the
// horizontal makes it fall, swing and fold, and keeps a non-zero vertical extent so the
// simulator's E_scale (m g times the height along gravity) is not zero.
namespace {
StudyScene tiltedCloth(const stabint::ClothGridParams& p) {
  const double tilt = 30.0 * M_PI / 180.0;
  StudyScene s;
  s.grid_nx = p.nx;
  s.grid_ny = p.ny;
  s.scene = stabint::makeClothGrid(p);
  Scene& sc = s.scene;
  for (int r = 0; r < sc.numParticles(); ++r) {
    const double x = sc.positions(r, 0);
    const double along = p.height - sc.positions(r, 1);  // distance from the pinned top edge
    sc.positions.row(r) << x, -along * std::sin(tilt), along * std::cos(tilt);
  }
  sc.rest_positions = sc.positions;  // elements keep their rest shape: a rigid rotation
  // The energy function does not depend on the tilt (pins lie on the rotation axis), so the
  // equilibrium is the untilted cloth hanging straight down from the same edge.
  s.equilibrium_start = sc.positions;
  for (int r = 0; r < sc.numParticles(); ++r) {
    const double along = std::hypot(sc.positions(r, 1), sc.positions(r, 2));
    s.equilibrium_start.row(r) << sc.positions(r, 0), -along, 0.0;
  }
  for (stabint::Pin& pin : sc.pins) pin.target.position = sc.positions.row(pin.vertex).transpose();
  stabint::validateScene(sc);
  return s;
}
}  // namespace

StudyScene clothScene(double stretch_stiffness) {
  stabint::ClothGridParams p;
  p.nx = 20;
  p.ny = 20;
  p.stretch_stiffness = stretch_stiffness;
  StudyScene s = tiltedCloth(p);
  s.key = stretch_stiffness == stabint::ClothGridParams{}.stretch_stiffness ? "cloth" : "cloth_stiff";
  s.params = "cloth nx=20 ny=20 w=" + fmt(p.width) + " h=" + fmt(p.height) + " rho=" + fmt(p.areal_density) +
             " ks=" + fmt(p.stretch_stiffness) + " kshear=" + fmt(p.shear_stiffness) + " kb=" + fmt(p.bend_stiffness) +
             " pin=" + fmt(p.pin_stiffness) + " tilt=30deg";
  // SE needs omega h < 2 on the corner pins (1e5 N/m on ~6e-5 kg: omega ~ 4e4 /s): h/2000 at
  // 1/30 gives omega h ~ 0.7. Issue 8 runs the stiff cloth (springs 1e6 N/m, highest lattice
  // mode ~ 2.4e5 /s) at h = 1/15 and judges how far it falls in 1 s: h/20000 there.
  if (s.key == "cloth_stiff") {
    s.frame_step = 1.0 / 15.0;
    s.reference_substeps = 20000;
    s.reference_seconds = 1.0;
  }
  return s;
}

StudyScene triangleClothScene(int n, double strain_stiffness, double strain_min) {
  stabint::ClothGridParams p;
  p.nx = n;
  p.ny = n;
  p.model = stabint::ClothModel::Triangles;
  p.strain_stiffness = strain_stiffness;
  p.strain_min = strain_min;
  p.hinge_stiffness = kTriangleClothHinge;
  StudyScene s = tiltedCloth(p);
  s.key = n == 20 && strain_min == 1.0 ? "cloth_triangles" : "cloth_triangles" + std::to_string(n);
  s.params = "cloth model=triangles nx=" + std::to_string(n) + " ny=" + std::to_string(n) + " w=" + fmt(p.width) +
             " h=" + fmt(p.height) + " rho=" + fmt(p.areal_density) + " kstrain=" + fmt(p.strain_stiffness) +
             " strain=[" + fmt(p.strain_min) + "," + fmt(p.strain_max) + "] khinge=" + fmt(p.hinge_stiffness) +
             " pin=" + fmt(p.pin_stiffness) + " tilt=30deg";
  // Corner pins as on the spring cloth (omega h ~ 0.7 at h/2000); only the sweep's 0-1 s error
  // needs this reference, so it stops at 2 s.
  s.reference_seconds = 2.0;
  return s;
}

StudyScene handleClothScene(double frequency) {
  StudyScene s;
  s.scene = stabint::loadSceneFile(std::string(STABINT_STUDY_SCENES_DIR) + "/cloth_handle.json");
  s.key = "handle";
  if (frequency != kHandleFrequency) {
    for (stabint::Pin& pin : s.scene.pins)
      if (pin.target.frequency > 0.0) pin.target.frequency = frequency;
    std::ostringstream key;
    key << "handle_" << frequency << "Hz";
    s.key = key.str();
  }
  s.params = "cloth_handle.json fingerprint=" + fingerprint(s.scene);
  return s;
}

StudyScene stiffDragScene() {
  StudyScene s;
  s.scene = stabint::loadSceneFile(std::string(STABINT_STUDY_SCENES_DIR) + "/cloth_stiff_drag.json");
  s.key = "stiff_drag";
  s.params = "cloth_stiff_drag.json fingerprint=" + fingerprint(s.scene) + " energy unit: the drive's";
  s.driven_energy_unit = true;  // it starts at rest in its rest shape
  return s;
}

StudyScene spinningBarScene(bool general, double omega) {
  StudyScene s = tetBarScene();
  s.key = general ? "spinbar_general" : "spinbar";
  Scene& sc = s.scene;
  sc.pins.clear();
  sc.gravity.setZero();
  const Eigen::Vector3d centre = centreOfMass(sc.positions, sc.masses);
  // 20 % stretch along the length about the centre: elastic energy that the spin must carry
  // through the tets' non-linear (co-rotated) response.
  if (general)
    for (Eigen::Index r = 0; r < sc.positions.rows(); ++r)
      sc.positions(r, 0) = centre.x() + 1.2 * (sc.positions(r, 0) - centre.x());
  const Eigen::Vector3d axis = general ? Eigen::Vector3d(1.0, 2.0, 3.0).normalized() : Eigen::Vector3d::UnitY();
  for (Eigen::Index r = 0; r < sc.positions.rows(); ++r)
    sc.velocities.row(r) = (omega * axis).cross(sc.positions.row(r).transpose() - centre).transpose();
  s.params += " free spin omega=" + fmt(omega) + (general ? " axis=(1,2,3) stretch=1.2" : " axis=y");
  return s;
}

StudyScene movingPinScene(double stiffness) {
  stabint::LinearOscillatorParams p;
  p.stiffness = stiffness;
  p.amplitude = 0.0;  // the particle starts on the pin's target, at rest
  StudyScene s;
  s.key = "moving_pin";
  s.scene = stabint::makeLinearOscillator(p);
  stabint::PinTarget& target = s.scene.pins.at(0).target;
  target.amplitude = Eigen::Vector3d(kMovingPinAmplitude, 0.0, 0.0);
  target.frequency = kMovingPinFrequency;
  s.params = "moving pin m=" + fmt(p.mass) + " k=" + fmt(stiffness) + " a=" + fmt(kMovingPinAmplitude) +
             " f=" + fmt(kMovingPinFrequency);
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
  // An SE step costs 270 us here (per-tet rotations) and the 1e7 N/m pins need h/200 for
  // stability alone: converged implicit midpoint at h/16 instead (energy error ~4e-5 E_avail).
  s.reference_integrator = Integrator::ImplicitMidpoint;
  s.reference_substeps = 16;
  s.reference_tolerance = 1e-10;
  return s;
}

std::string cacheDescription(const StudyScene& scene) {
  std::ostringstream t;
  t.precision(17);
  t << scene.params;
  auto put = [&t](const Eigen::Vector3d& v) { t << ' ' << v.x() << ' ' << v.y() << ' ' << v.z(); };
  for (const stabint::Collider& c : scene.scene.colliders) {
    t << " collider shape=" << static_cast<int>(c.shape);
    put(c.center);
    put(c.normal);
    put(c.half_extents);
    put(c.end);
    t << ' ' << c.radius;
    put(c.velocity);
    t << " mu=" << c.friction << " k=" << c.stiffness;
  }
  return t.str();
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
  double previous = sim.energy().elastic + sim.energy().external, lowest = previous;
  for (int step = 0; step < 400; ++step) {
    sim.step();
    const double now = sim.energy().elastic + sim.energy().external;
    lowest = std::min(lowest, now);
    if (std::abs(previous - now) <= 1e-12 * std::max(1.0, std::abs(now))) break;
    previous = now;
  }
  // The lowest potential visited: where the solves hit their iteration cap (the stiff chain's
  // 1e6 N/m springs at this step) the descent can swing through the equilibrium instead of
  // settling in it, and the stop above then meets two equal potentials anywhere on the swing
  // (E_avail 0.055 instead of 0.49 for that chain).
  return lowest;
}

double availableEnergy(const StudyScene& scene) {
  stabint::SimulatorOptions o;
  o.integrator = Integrator::BackwardEuler;
  stabint::Simulator sim(scene.scene, o);
  return sim.energy().total() - equilibriumPotential(scene.scene, scene.equilibrium_start);
}

}  // namespace study
