// `contact`: issue 45's contact table. Soft bodies of three stiffnesses (a 16 x 4 x 4 tet bar,
// 1 m x 0.25 m x 0.25 m, 62.5 kg, at 1e5, 1e6 and 1e7 Pa) thrown from 5 cm above a collider at 1, 3
// and 6 m/s onto a plane, a sphere (radius 0.5 m) and a box (0.6 m x 0.2 m x 0.6 m), each under the
// bar's centre with its top at 0, friction 0.5, with BE, BDF2, IM and the blend and every contact
// option at its default. Per run: max(H - H*) over the run's largest kinetic energy (the energy
// books: H may not run above the target that books every input and loss), the deepest a vertex
// is inside a collider after a step, the rebound (the centre's highest point after the impact
// above its lowest, over the height the fall would reach at rest) and ms per frame. Writes
// contact_table.csv and contact_table.md (a row per body, speed and collider, a column group per
// integrator) and prints the Markdown.
#include "csv.hpp"
#include "study.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace study {

namespace {

constexpr double kLift = 0.05;     // m: the bar's bottom above the collider's top at the start
constexpr double kFriction = 0.5;  // every collider's
constexpr double kSeconds = 2.0;   // per run

struct ContactRun {
  double excess = 0.0;  // max(H - H*) / K_max
  double deepest = 0.0;
  double rebound = 0.0;
  double ms = 0.0;
  bool refused = false;
};

stabint::Collider colliderUnderTheBar(const std::string& shape, const Eigen::Vector3d& centre) {
  stabint::Collider c;
  c.friction = kFriction;
  if (shape == "sphere") {
    c.shape = stabint::ColliderShape::Sphere;
    c.radius = 0.5;
    c.center = Eigen::Vector3d(centre.x(), -0.5, centre.z());
  } else if (shape == "box") {
    c.shape = stabint::ColliderShape::Box;
    c.half_extents = Eigen::Vector3d(0.3, 0.1, 0.3);
    c.center = Eigen::Vector3d(centre.x(), -0.1, centre.z());
  } else {
    c.shape = stabint::ColliderShape::Plane;
  }
  return c;
}

// How deep x is inside collider c (translating with its scene velocity, here none): 0 outside.
double depthInside(const stabint::Collider& c, const Eigen::Vector3d& x) {
  switch (c.shape) {
    case stabint::ColliderShape::Plane: return std::max(0.0, -(x - c.center).dot(c.normal.normalized()));
    case stabint::ColliderShape::Sphere: return std::max(0.0, c.radius - (x - c.center).norm());
    case stabint::ColliderShape::Box: {
      const Eigen::Vector3d q = (x - c.center).cwiseAbs() - c.half_extents;
      return std::max(0.0, -q.maxCoeff());
    }
    case stabint::ColliderShape::Capsule:
    case stabint::ColliderShape::Mesh: break;  // the table throws onto the other three
  }
  return 0.0;
}

ContactRun throwBar(const Scene& scene, Integrator integrator, const StudyOptions& options, double fall, int frames) {
  stabint::SimulatorOptions o;
  o.integrator = integrator;
  o.backend = options.backend;
  stabint::Simulator sim(scene, o);
  ContactRun run;
  const double mass = scene.masses.sum();
  auto centre = [&](const Eigen::MatrixX3d& x) { return scene.masses.dot(x.col(1)) / mass; };
  double largest_kinetic = 0.0, excess = -1e300, lowest = centre(sim.positions()), seconds = 0.0;
  bool landed = false;
  int done = 0;
  for (; done < frames; ++done) {
    const auto t0 = std::chrono::steady_clock::now();
    try {
      sim.step();
    } catch (const stabint::Error&) {
      run.refused = true;  // a blow-up: the table says so
      break;
    }
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const stabint::StepReport& r = sim.lastReport();
    excess = std::max(excess, r.energy.total() - r.target);
    largest_kinetic = std::max(largest_kinetic, r.energy.kinetic);
    const Eigen::MatrixX3d& x = sim.positions();
    for (Eigen::Index j = 0; j < x.rows(); ++j)
      run.deepest = std::max(run.deepest, depthInside(scene.colliders[0], x.row(j).transpose()));
    const double y = centre(x);
    if (!landed && y > lowest) landed = true;
    if (!landed) lowest = std::min(lowest, y);
    if (landed) run.rebound = std::max(run.rebound, (y - lowest) / fall);
  }
  run.excess = largest_kinetic > 0.0 ? excess / largest_kinetic : 0.0;  // 0: refused at its first step
  run.ms = done > 0 ? 1e3 * seconds / done : 0.0;
  return run;
}

}  // namespace

void runContact(const StudyOptions& options) {
  ensureDirectory(options.out);
  const std::vector<double> stiffnesses = options.quick ? std::vector<double>{1e6} : std::vector<double>{1e5, 1e6, 1e7};
  const std::vector<double> speeds = options.quick ? std::vector<double>{3.0} : std::vector<double>{1.0, 3.0, 6.0};
  const std::vector<std::string> shapes = {"plane", "sphere", "box"};
  const std::vector<Integrator> integrators = {Integrator::BackwardEuler, Integrator::BDF2,
                                               Integrator::ImplicitMidpoint, Integrator::EnergyBlend};
  const int frames = options.quick ? 15 : static_cast<int>(kSeconds * 30.0 + 0.5);
  CsvWriter csv(joinPath(options.out, "contact_table.csv"),
                {"stiffness_pa", "speed", "collider", "integrator", "backend", "excess_over_kmax", "deepest_m",
                 "rebound", "ms_per_frame", "refused"});
  std::string md = "| body | speed | collider |";
  for (Integrator i : integrators) md += std::string(" ") + stabint::integratorName(i) + " |";
  md += "\n|---|---:|---|";
  for (std::size_t i = 0; i < integrators.size(); ++i) md += "---|";
  md += "\n";
  const double g = 9.81;
  for (double stiffness : stiffnesses) {
    for (double speed : speeds) {
      for (const std::string& shape : shapes) {
        stabint::TetBarParams p;
        p.nx = 16;
        p.ny = p.nz = 4;
        p.stiffness = stiffness;
        Scene s = stabint::makeTetBar(p);
        s.pins.clear();
        s.positions.col(1).array() += kLift - s.positions.col(1).minCoeff();
        s.velocities.col(1).setConstant(-speed);
        const Eigen::Vector3d centre = s.positions.colwise().mean().transpose();
        s.colliders.push_back(colliderUnderTheBar(shape, centre));
        // The height of a fall from rest that arrives at the same speed.
        const double fall = kLift + speed * speed / (2.0 * g);
        char row[96];
        std::snprintf(row, sizeof row, "| %g Pa | %g m/s | %s |", stiffness, speed, shape.c_str());
        md += row;
        for (Integrator integrator : integrators) {
          const ContactRun r = throwBar(s, integrator, options, fall, frames);
          csv << stiffness << speed << shape << stabint::integratorName(integrator)
              << stabint::backendName(options.backend) << r.excess << r.deepest << r.rebound << r.ms
              << (r.refused ? 1 : 0);
          csv.endRow();
          char cell[96];
          if (r.refused)
            std::snprintf(cell, sizeof cell, " refused |");
          else
            std::snprintf(cell, sizeof cell, " %.3f, %.1f mm, %.0f %%, %.1f ms |", r.excess, 1e3 * r.deepest,
                          100.0 * r.rebound, r.ms);
          md += cell;
        }
        md += "\n";
      }
    }
  }
  md +=
      "\nEach cell: max(H - H*) / K_max, the deepest vertex after a step, the rebound (% of the fall), ms "
      "per frame.\n";
  std::ofstream(joinPath(options.out, "contact_table.md")) << md;
  std::printf("%s", md.c_str());
  std::fflush(stdout);
}

}  // namespace study
