// `drop`: a soft body made by a real mesher dropped onto the ground, BE, BDF2 and the blend side
// by side (issue 23). The tet mesh is TetGen's (scripts/soft_body_mesh.sh meshes CGAL's elephant
// surface from Debian's libcgal-demo); this command scales it, tilts it and drops it onto a
// ground plane with friction, at h = 1/30 s and the default 10 iterations. Writes the body's
// boundary surface (drop_surface.csv, outward triangles of the tets), the positions of every
// frame per integrator (drop_<integrator>.bin: float32 little-endian, frames x particles x 3,
// frame 0 the start) and every frame's energies (drop_energy.csv); bench/drop.py renders them.
// Prints a table per integrator: how much of the energy the fall made available is left, the
// rebound and the late mean kinetic energy, so the caption can say what the pictures show.
#include "csv.hpp"
#include "study.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <stdexcept>
#include <vector>

namespace study {

namespace {

// The body: scaled so its longest side is kSize, a rubber-like solid with the tet bar's density
// and stiffness (a fifth of it lets the thin legs fold flat under the impact).
constexpr double kSize = 0.6;         // m
constexpr double kDensity = 1000.0;   // kg/m^3
constexpr double kStiffness = 3e5;    // Pa
constexpr double kDropHeight = 0.3;   // m: its lowest point above the ground at the start
constexpr double kTiltDegrees = 5.0;  // nose down (the trunk points along +x): front feet first, then it rocks
// The ground of `interaction`'s bounce: every contact option at its default (a contact as stiff as
// the body's elements, docs/method.md "Contact"), with friction.
constexpr double kGroundFriction = 0.3;
constexpr double kSeconds = 4.0;
constexpr double kLateSeconds = 1.0;  // the mean kinetic energy over the last second

// The mesh as loaded, scaled to kSize, tilted, centred over the origin and lifted kDropHeight
// above the ground; masses lumped again for the scaled volume.
Scene dropScene(const std::string& mesh) {
  stabint::SolidMaterial material;
  material.density = kDensity;
  material.stiffness = kStiffness;
  Scene s = loadTetGenMesh(mesh, material);
  const Eigen::Vector3d lo = s.rest_positions.colwise().minCoeff(), hi = s.rest_positions.colwise().maxCoeff();
  const double scale = kSize / (hi - lo).maxCoeff();
  const Eigen::RowVector3d mid = (0.5 * (lo + hi)).transpose();
  s.rest_positions = ((s.rest_positions.rowwise() - mid) * scale).eval();
  s.masses = stabint::lumpMassesFromTets(s.rest_positions, s.tets, kDensity);
  const double tilt = kTiltDegrees * M_PI / 180.0;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(-tilt, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  s.positions = s.rest_positions * turn.transpose();
  s.positions.col(1).array() += kDropHeight - s.positions.col(1).minCoeff();
  s.velocities.setZero(s.positions.rows(), 3);
  stabint::Collider ground;
  ground.shape = stabint::ColliderShape::Plane;
  ground.friction = kGroundFriction;
  s.colliders.push_back(ground);
  s.name = "drop";
  return s;
}

}  // namespace

void runDrop(const StudyOptions& options) {
  if (options.mesh.empty())
    throw stabint::InvalidInputError("drop needs --mesh BASE (a TetGen .node/.ele pair; scripts/soft_body_mesh.sh)");
  ensureDirectory(options.out);
  const Scene scene = dropScene(options.mesh);
  const std::vector<std::array<int, 3>> surface = stabint::tetSurface(scene.tets);
  {
    CsvWriter tri(joinPath(options.out, "drop_surface.csv"), {"a", "b", "c"});
    for (const auto& t : surface) {
      tri << t[0] << t[1] << t[2];
      tri.endRow();
    }
  }
  progress("drop: " + std::to_string(scene.numParticles()) + " particles, " + std::to_string(scene.tets.size()) +
           " tets, " + std::to_string(surface.size()) + " surface triangles, " + std::to_string(scene.masses.sum()) +
           " kg");
  const int frames = options.quick ? 30 : static_cast<int>(kSeconds * 30.0 + 0.5);
  const int late = std::min(frames, static_cast<int>(kLateSeconds * 30.0 + 0.5));
  CsvWriter csv(joinPath(options.out, "drop_energy.csv"),
                {"integrator", "backend", "particles", "frame", "time", "H", "H_target", "kinetic", "elastic",
                 "external", "friction", "com_height", "ms_per_frame"});
  const double total_mass = scene.masses.sum();
  auto comHeight = [&](const Eigen::MatrixX3d& x) { return scene.masses.dot(x.col(1)) / total_mass; };
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::BDF2, Integrator::EnergyBlend}) {
    stabint::SimulatorOptions o;
    o.integrator = integrator;
    o.backend = options.backend;
    stabint::Simulator sim(scene, o);
    std::ofstream bin(joinPath(options.out, std::string("drop_") + stabint::integratorName(integrator) + ".bin"),
                      std::ios::binary | std::ios::trunc);
    if (!bin)
      throw std::runtime_error("cannot write drop_" + std::string(stabint::integratorName(integrator)) + ".bin");
    appendPositions(bin, sim.positions());
    const stabint::EnergyReport e0 = sim.energy();
    const double h0 = e0.total(), com0 = comHeight(sim.positions());
    csv << stabint::integratorName(integrator) << stabint::backendName(options.backend) << scene.numParticles() << 0
        << 0.0 << h0 << h0 << e0.kinetic << e0.elastic << e0.external << 0.0 << com0 << 0.0;
    csv.endRow();
    double friction = 0.0, seconds = 0.0, late_kinetic = 0.0, rebound = 0.0, lowest = com0;
    double excess = 0.0, largest_kinetic = 0.0;  // max(H - H*) and max K: the books at the impacts
    bool landed = false;
    for (int f = 1; f <= frames; ++f) {
      const auto t0 = std::chrono::steady_clock::now();
      const stabint::StepReport& r = sim.step();
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      friction += r.friction;
      excess = std::max(excess, r.energy.total() - r.target);
      largest_kinetic = std::max(largest_kinetic, r.energy.kinetic);
      const double com = comHeight(sim.positions());
      // Landed once the centre of mass stops falling; the rebound is the highest it climbs
      // above the lowest point of the impact after that.
      if (!landed && com > lowest) landed = true;
      if (!landed) lowest = std::min(lowest, com);
      if (landed) rebound = std::max(rebound, com - lowest);
      if (f > frames - late) late_kinetic += r.energy.kinetic;
      appendPositions(bin, sim.positions());
      csv << stabint::integratorName(integrator) << stabint::backendName(options.backend) << scene.numParticles() << f
          << r.time << r.energy.total() << r.target << r.energy.kinetic << r.energy.elastic << r.energy.external
          << friction << com << 1e3 * seconds / f;
      csv.endRow();
    }
    if (!bin) throw std::runtime_error("write failed: drop positions");
    const stabint::EnergyReport end = sim.energy();
    // The energy the fall makes available: H_0 less the potential of the body lying on the
    // ground, which the printed H_end approaches from above; friction is what the ground took.
    std::printf(
        "  drop %-5s %.3g ms/frame, H %.4g J -> %.4g J (friction %.3g J), rebound of the centre %.3g m, "
        "mean K over the last second %.3g J, max(H - H*) %.3g of the largest K\n",
        stabint::integratorName(integrator), 1e3 * seconds / frames, h0, end.total(), friction, rebound,
        late_kinetic / late, excess / largest_kinetic);
    std::fflush(stdout);
  }
}

}  // namespace study
