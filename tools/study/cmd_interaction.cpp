// `interaction`: issue 10's grab-drag-release through the per-frame input API. A 20 x 20 cloth
// hangs from its top corners; at 0.5 s a hand grabs its free bottom corner, lifts it out of the
// cloth's plane and across for 1 s, holds it for 0.5 s and lets go; the run goes on to 6 s. BE,
// BDF2 and the blend, each with H, H*, the hand's work (forcing) and the grab/release events
// per frame (interaction.csv). Then a bounce: the free tet bar dropped onto the ground, with the
// same three integrators, each with H, H*, and the friction and final-projection terms of H*
// (bounce.csv).
#include "csv.hpp"
#include "study.hpp"

#include <cmath>
#include <cstdio>

namespace study {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kGrabAt = 0.5, kDragFor = 1.0, kReleaseAt = 2.0;
constexpr double kHandleStiffness = 1e4;  // N/m, ten times the cloth's stretch springs

// The hand's offset from where it grabbed, at time t: smooth (it starts and stops at rest).
Eigen::Vector3d handOffset(double t) {
  const double s = std::clamp((t - kGrabAt) / kDragFor, 0.0, 1.0);
  const double ease = 0.5 * (1.0 - std::cos(kPi * s));
  return Eigen::Vector3d(0.3 * ease, 0.15 * ease, 0.4 * std::sin(kPi * s) + 0.1 * ease);
}

// The default tet bar (62.5 kg) without pins, its bottom 0.5 m above a ground plane with every
// contact option at its default (docs/method.md, "Contact": a contact as stiff as the bar's
// elements, so it stops on its bottom layer and what it keeps of its bounce is the integrator's
// and the material's doing). The ground has Coulomb friction 0.3, so the flexing bar's sideways
// slips show in the books.
constexpr double kDrop = 0.5, kGroundFriction = 0.3;
constexpr double kBarRestHeight = 0.125;  // half the bar's width: its centre when it lies on the ground

void runBounce(const StudyOptions& options) {
  stabint::Scene bar = stabint::makeTetBar(stabint::TetBarParams{});
  bar.pins.clear();
  bar.positions.col(1).array() += kDrop - bar.positions.col(1).minCoeff();
  stabint::Collider ground;
  ground.shape = stabint::ColliderShape::Plane;
  ground.friction = kGroundFriction;
  bar.colliders.push_back(ground);
  const int frames = options.quick ? 60 : 120;
  CsvWriter csv(joinPath(options.out, "bounce.csv"), {"integrator", "backend", "frame", "time", "H", "H_target",
                                                      "kinetic", "friction", "projection", "height", "E_scale"});
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::BDF2, Integrator::EnergyBlend}) {
    stabint::SimulatorOptions o;
    o.integrator = integrator;
    o.backend = options.backend;
    stabint::Simulator sim(bar, o);
    double friction = 0.0, projection = 0.0, worst_gap = 0.0;
    // When the centre first reaches its resting height, and the highest it gets after that (the
    // rebound, as a fraction of the drop). Local maxima of the height would count the bar's
    // elastic vibration as bounces.
    double landed_at = -1.0, rebound = 0.0;
    for (int f = 0; f < frames; ++f) {
      const stabint::StepReport& r = sim.step();
      friction += r.friction;
      projection += r.contact_projection;
      worst_gap = std::max(worst_gap, std::abs(r.energy.total() - r.target) / sim.energyScale());
      const double y = sim.positions().col(1).mean();
      if (landed_at < 0.0 && y <= kBarRestHeight) landed_at = r.time;
      if (landed_at >= 0.0) rebound = std::max(rebound, (y - kBarRestHeight) / kDrop);
      csv << stabint::integratorName(integrator) << stabint::backendName(options.backend) << f + 1 << r.time
          << r.energy.total() << r.target << r.energy.kinetic << friction << projection << y - kBarRestHeight
          << sim.energyScale();
      csv.endRow();
    }
    std::printf(
        "  bounce      %-5s lands at %.3g s, rebounds to %.2f of the drop, friction %.4g J, "
        "projection %.4g J, max |H - H*| %.3g E_scale\n",
        stabint::integratorName(integrator), landed_at, rebound, friction, projection, worst_gap);
    std::fflush(stdout);
  }
}

}  // namespace

void runInteraction(const StudyOptions& options) {
  ensureDirectory(options.out);
  stabint::ClothGridParams p;
  p.nx = p.ny = 20;
  const stabint::Scene cloth = stabint::makeClothGrid(p);
  const int corner = p.nx * (p.ny - 1);  // bottom-left, free
  const int frames = options.quick ? 90 : 180;
  CsvWriter csv(joinPath(options.out, "interaction.csv"),
                {"integrator", "backend", "frame", "time", "H", "H_target", "kinetic", "elastic", "external", "work",
                 "events", "E_scale", "held"});
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::BDF2, Integrator::EnergyBlend}) {
    stabint::SimulatorOptions o;
    o.integrator = integrator;
    o.backend = options.backend;
    stabint::Simulator sim(cloth, o);
    const double h = o.time_step;
    int handle = -1;
    Eigen::Vector3d grabbed_at = Eigen::Vector3d::Zero();
    double work = 0.0, events = 0.0, worst_gap = 0.0, late_kinetic = 0.0;
    int late_frames = 0;
    for (int f = 0; f < frames; ++f) {
      const double t1 = (f + 1) * h;
      if (handle < 0 && t1 > kGrabAt && t1 <= kReleaseAt) {
        grabbed_at = sim.positions().row(corner).transpose();
        handle = sim.grab(corner, kHandleStiffness);
      }
      const bool held = handle >= 0 && sim.scene().pins[handle].stiffness > 0.0;
      if (held && t1 > kReleaseAt) {
        sim.release(handle);
      } else if (held) {
        sim.setPinTarget(handle, grabbed_at + handOffset(t1));
      }
      const stabint::StepReport& r = sim.step();
      work += r.forcing;
      events += r.event_energy;
      worst_gap = std::max(worst_gap, std::abs(r.energy.total() - r.target) / sim.energyScale());
      if (r.time > kReleaseAt + 2.0) {
        late_kinetic += r.energy.kinetic;
        ++late_frames;
      }
      csv << stabint::integratorName(integrator) << stabint::backendName(options.backend) << f + 1 << r.time
          << r.energy.total() << r.target << r.energy.kinetic << r.energy.elastic << r.energy.external << work << events
          << sim.energyScale() << (held && t1 <= kReleaseAt ? 1 : 0);
      csv.endRow();
    }
    std::printf(
        "  interaction %-5s hand's work %.4g J, release %.4g J, max |H - H*| %.3g E_scale, "
        "mean K from 2 s after the release %.3g J\n",
        stabint::integratorName(integrator), work, events, worst_gap,
        late_frames > 0 ? late_kinetic / late_frames : 0.0);
    std::fflush(stdout);
  }
  runBounce(options);
  progress("interaction done");
}

}  // namespace study
