// `fold`: self-contact's study scene (issue 49). A 40 x 40 spring cloth stands almost upright
// beside a body given as a triangle mesh (a static mesh collider: the surface of a TetGen mesh,
// scripts/soft_body_mesh.sh's elephant in the main job). It collapses and folds onto itself on the
// ground; at 1.5 s a hand grabs the middle of its top edge (Simulator::grab) and drags it up and
// over the body (setPinTarget every frame), pulling the folded cloth after it. Self-contact on
// (4 mm), BE, BDF2 and the blend from the same start (h = 1/30 s, the default 10 iterations).
// Writes the cloth's triangles (fold_triangles.csv), the body's surface (fold_body.csv: the
// vertices, then the triangles), the positions of every frame per integrator
// (fold_<integrator>.bin: float32 little-endian, frames x particles x 3, frame 0 the start) and
// every frame's energies (fold_energy.csv); bench/fold.py renders them.
#include "csv.hpp"
#include "study.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace study {

namespace {

constexpr int kClothSide = 40;
constexpr double kBodySize = 0.5;       // m: the body's longest side
constexpr double kTilt = 0.3;           // rad: the cloth leans away from the body by this
constexpr double kEdge = -0.4;          // m: x of the cloth's lower edge
constexpr double kThickness = 4e-3;     // m: self_contact_thickness
constexpr double kBendStiffness = 1.0;  // N/m: a soft bend, so that the cloth folds
constexpr double kGroundFriction = 0.5;
constexpr double kBodyFriction = 0.1;
constexpr double kGrabTime = 1.5;       // s
constexpr double kHandStiffness = 1e4;  // N/m
constexpr double kHandSpeed = 0.4;      // m/s along +x, over the body
constexpr double kHandLift = 0.8;       // m above where it grabbed, reached at 1 m/s
constexpr double kSeconds = 6.0;

// The body: the surface of the TetGen mesh `mesh`, scaled so that its longest side is kBodySize,
// centred over the origin and standing on the ground.
stabint::Collider bodyCollider(const std::string& mesh) {
  const Scene solid = loadTetGenMesh(mesh, stabint::SolidMaterial{});
  const Eigen::Vector3d lo = solid.rest_positions.colwise().minCoeff(), hi = solid.rest_positions.colwise().maxCoeff();
  const double scale = kBodySize / (hi - lo).maxCoeff();
  stabint::Collider body;
  body.shape = stabint::ColliderShape::Mesh;
  body.friction = kBodyFriction;
  body.center.setZero();
  body.mesh_triangles = stabint::tetSurface(solid.tets);
  body.mesh_vertices = (solid.rest_positions.rowwise() - (0.5 * (lo + hi)).transpose()) * scale;
  body.mesh_vertices.col(1).array() -= body.mesh_vertices.col(1).minCoeff();
  return body;
}

// The cloth beside the body: its lower edge along z at x = kEdge, 2 cm above the ground, its
// plane leaning away from the body by kTilt; no pins.
Scene foldScene(const std::string& mesh, int side) {
  stabint::ClothGridParams p;
  p.nx = p.ny = side;
  p.bend_stiffness = kBendStiffness;
  Scene s = stabint::makeClothGrid(p);
  s.pins.clear();
  const double x_min = s.positions.col(0).minCoeff(), y_min = s.positions.col(1).minCoeff();
  const double width = s.positions.col(0).maxCoeff() - x_min;
  for (int i = 0; i < s.numParticles(); ++i) {
    const double across = s.positions(i, 0) - x_min - 0.5 * width, up = s.positions(i, 1) - y_min;
    s.positions.row(i) << kEdge - up * std::sin(kTilt), 0.02 + up * std::cos(kTilt), across;
  }
  s.rest_positions = s.positions;
  stabint::Collider ground;
  ground.shape = stabint::ColliderShape::Plane;
  ground.friction = kGroundFriction;
  s.colliders = {ground, bodyCollider(mesh)};
  s.name = "fold";
  return s;
}

// The particle the hand grabs: the middle of the top edge.
int handle(const Scene& s) {
  int best = 0;
  for (int i = 0; i < s.numParticles(); ++i) {
    const auto score = [&](int k) { return s.positions(k, 1) - std::abs(s.positions(k, 2)); };
    if (score(i) > score(best)) best = i;
  }
  return best;
}

}  // namespace

void runFold(const StudyOptions& options) {
  if (options.mesh.empty())
    throw stabint::InvalidInputError("fold needs --mesh BASE (a TetGen .node/.ele pair; scripts/soft_body_mesh.sh)");
  ensureDirectory(options.out);
  const Scene scene = foldScene(options.mesh, options.quick ? 12 : kClothSide);
  {
    CsvWriter tri(joinPath(options.out, "fold_triangles.csv"), {"a", "b", "c"});
    for (const auto& t : scene.triangles) {
      tri << t[0] << t[1] << t[2];
      tri.endRow();
    }
    const stabint::Collider& body = scene.colliders.back();
    CsvWriter out(joinPath(options.out, "fold_body.csv"), {"kind", "a", "b", "c"});
    for (Eigen::Index v = 0; v < body.mesh_vertices.rows(); ++v) {
      out << "v" << body.mesh_vertices(v, 0) << body.mesh_vertices(v, 1) << body.mesh_vertices(v, 2);
      out.endRow();
    }
    for (const auto& t : body.mesh_triangles) {
      out << "f" << t[0] << t[1] << t[2];
      out.endRow();
    }
  }
  const int held = handle(scene);
  progress("fold: " + std::to_string(scene.numParticles()) + " particles, a body of " +
           std::to_string(scene.colliders.back().mesh_triangles.size()) + " triangles");
  const int frames = options.quick ? 30 : static_cast<int>(kSeconds * 30.0 + 0.5);
  CsvWriter csv(joinPath(options.out, "fold_energy.csv"),
                {"integrator", "backend", "particles", "frame", "time", "H", "H_target", "kinetic", "elastic",
                 "external", "ms_per_frame"});
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::BDF2, Integrator::EnergyBlend}) {
    stabint::SimulatorOptions o;
    o.integrator = integrator;
    o.backend = options.backend;
    o.self_contact_thickness = kThickness;
    stabint::Simulator sim(scene, o);
    const char* name = stabint::integratorName(integrator);
    std::ofstream bin(joinPath(options.out, std::string("fold_") + name + ".bin"), std::ios::binary | std::ios::trunc);
    if (!bin) throw std::runtime_error(std::string("cannot write fold_") + name + ".bin");
    appendPositions(bin, sim.positions());
    const stabint::EnergyReport e0 = sim.energy();
    csv << name << stabint::backendName(options.backend) << scene.numParticles() << 0 << 0.0 << e0.total() << e0.total()
        << e0.kinetic << e0.elastic << e0.external << 0.0;
    csv.endRow();
    double seconds = 0.0, excess = 0.0, largest_kinetic = 0.0, booked = 0.0;
    int done = 0, hand = -1;
    Eigen::Vector3d grabbed = Eigen::Vector3d::Zero();
    const double grab_time = options.quick ? 0.5 : kGrabTime;
    try {
      for (int f = 1; f <= frames; ++f) {
        const auto t0 = std::chrono::steady_clock::now();
        if (hand < 0 && sim.time() >= grab_time - 1e-9) {
          grabbed = sim.positions().row(held).transpose();
          hand = sim.grab(held, kHandStiffness);
        }
        if (hand >= 0) {
          const double t = sim.time() + o.time_step - grab_time;
          sim.setPinTarget(hand, grabbed + Eigen::Vector3d(kHandSpeed * t, std::min(kHandLift, t), 0.0));
        }
        const stabint::StepReport& r = sim.step();
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        excess = std::max(excess, r.energy.total() - r.target);
        largest_kinetic = std::max(largest_kinetic, r.energy.kinetic);
        booked += r.contact_projection;
        appendPositions(bin, sim.positions());
        csv << name << stabint::backendName(options.backend) << scene.numParticles() << f << r.time << r.energy.total()
            << r.target << r.energy.kinetic << r.energy.elastic << r.energy.external << 1e3 * seconds / f;
        csv.endRow();
        done = f;
      }
    } catch (const stabint::NonFiniteStateError& e) {
      std::printf("  fold %-5s refused at frame %d: %s\n", name, done + 1, e.what());
    }
    if (!bin) throw std::runtime_error("write failed: fold positions");
    const stabint::EnergyReport end = sim.energy();
    std::printf(
        "  fold %-5s %d frames, %.3g ms/frame, H %.4g J -> %.4g J, contact losses booked %.3g J, "
        "max(H - H*) %.3g of the largest K\n",
        name, done, 1e3 * seconds / std::max(done, 1), e0.total(), end.total(), booked,
        excess / std::max(largest_kinetic, 1e-300));
    std::fflush(stdout);
  }
}

}  // namespace study
