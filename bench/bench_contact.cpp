// Two scenes stepped interleaved in one run (the machine is noisy), each restarting from its
// first state every 90 steps (3 s: the fall, the landing and the settling), so the timed steps
// mix all three:
// - contact_vs_none: a 50 x 50 cloth dropped flat onto a sphere and the ground (friction 0.5)
//   against the same cloth without colliders; the counter `contact_vs_none` is the colliders'
//   step time over the plain one (issue 10: at most 1.15);
// - mesh_vs_sphere: the cloth onto an icosphere mesh of 20,480 triangles and the ground against
//   the analytic sphere's (docs/method.md, "Mesh colliders"); `mesh_vs_sphere` is the ratio;
// - self_vs_none: a cloth crumpling onto the ground with self-contact (4 mm) against the same
//   cloth without (docs/method.md, "Self-contact"); `self_vs_none` is the ratio.
// The others split each run's step into its phases (`_solves`: the local steps, gathers,
// transfers and global solves; `_energy`: the energy passes; `_bookkeeping`: the rest, the
// contact set and its changes of the factors and a mesh's queries included) and count its
// BE-partner steps (the share of steps), iterations and energy passes.
#include "bench_common.hpp"
#include "contact_scenes.hpp"

#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"

#include <chrono>
#include <exception>
#include <vector>

namespace stabint::bench {
namespace {

// The 50 x 50 spring cloth (1 m) lying flat at y = 0.5 without its pins.
Scene flatCloth() {
  Scene s = clothScene(50);
  s.pins.clear();
  for (Eigen::MatrixX3d* m : {&s.positions, &s.rest_positions}) {
    Eigen::MatrixX3d r(m->rows(), 3);
    r.col(0) = m->col(0).array() - m->col(0).mean();
    r.col(1).setConstant(0.5);
    r.col(2) = m->col(1).array() - m->col(1).mean();
    *m = r;
  }
  return s;
}

Scene clothOnSphereAndGround() {
  Scene s = flatCloth();
  Collider sphere;
  sphere.shape = ColliderShape::Sphere;
  sphere.center = Eigen::Vector3d(0.0, -0.1, 0.0);
  sphere.radius = 0.25;
  sphere.friction = 0.5;
  Collider ground;
  ground.shape = ColliderShape::Plane;
  ground.friction = 0.5;
  s.colliders = {sphere, ground};
  return s;
}

// The cloth over a mesh of the sphere: its vertices on the sphere, 5 subdivisions.
Scene clothOnMeshSphereAndGround() {
  Scene s = clothOnSphereAndGround();
  const Collider& sphere = s.colliders.front();
  s.colliders.front() = testing::icosphereCollider(sphere.center, sphere.radius, 5, sphere.friction);
  return s;
}

// The scenes of one comparison, the names of its counters, and the first one's self-contact
// thickness (SimulatorOptions::self_contact_thickness).
struct Comparison {
  Scene (*first)();
  Scene (*second)();
  const char* first_name;
  const char* second_name;
  double first_self_contact = 0.0;
};
const Comparison kContactVsNone{clothOnSphereAndGround, flatCloth, "contact", "none"};
const Comparison kMeshVsSphere{clothOnMeshSphereAndGround, clothOnSphereAndGround, "mesh", "sphere"};
// The crumpling cloth (tests/contact_scenes.hpp) of n x n particles with and without
// self-contact at 4 mm.
template <int n>
Scene crumplingCloth() {
  return testing::crumplingCloth(n);
}
const Comparison kSelfVsNone{crumplingCloth<50>, crumplingCloth<50>, "self", "none", 4e-3};
const Comparison kSelfVsNone100{crumplingCloth<100>, crumplingCloth<100>, "self", "none", 4e-3};
const Comparison kSelfVsNone200{crumplingCloth<200>, crumplingCloth<200>, "self", "none", 4e-3};

struct ContactFixture {
  std::unique_ptr<Simulator> first, second;
  Checkpoint first_start, second_start;
};

void runContact(benchmark::State& state, const std::string& key, BackendChoice backend, Integrator integrator,
                const Comparison& comparison) {
  if (const std::string why = skipReason(backend); !why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  ContactFixture* fixture = nullptr;
  try {
    fixture = &cachedFixture<ContactFixture>(key, [&] {
      auto f = std::make_unique<ContactFixture>();
      const SimulatorOptions o = optionsFor(backend, integrator);
      SimulatorOptions first_options = o;
      first_options.self_contact_thickness = comparison.first_self_contact;
      f->first = std::make_unique<Simulator>(comparison.first(), first_options);
      f->second = std::make_unique<Simulator>(comparison.second(), o);
      f->first_start = f->first->checkpoint();
      f->second_start = f->second->checkpoint();
      return f;
    });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  ContactFixture& f = *fixture;
  using Clock = std::chrono::steady_clock;
  double first_time = 0, second_time = 0;
  // Where the time goes, per run: the phases, the blend's BE-partner steps, the iterations and
  // energy passes.
  struct Sums {
    PhaseTimes times;
    double partner_steps = 0, iterations = 0, energy_passes = 0;
  } first_sums, second_sums;
  auto timed = [](double& sum, Sums& sums, Simulator& sim) {
    const auto start = Clock::now();
    const StepReport& r = sim.step();
    sum += std::chrono::duration<double>(Clock::now() - start).count();
    sums.times += r.times;
    sums.partner_steps += r.branch == BlendBranch::BackwardEuler ? 1 : 0;
    sums.iterations += r.iterations;
    sums.energy_passes += r.energy_evaluations;
  };
  try {
    for (auto _ : state) {
      if (f.first->stepCount() >= 90) {
        f.first->restore(f.first_start);
        f.second->restore(f.second_start);
      }
      timed(first_time, first_sums, *f.first);
      timed(second_time, second_sums, *f.second);
    }
  } catch (const NonFiniteStateError& e) {
    state.SkipWithError(e.what());
    return;
  }
  using benchmark::Counter;
  const std::string first = comparison.first_name, second = comparison.second_name;
  state.counters[first + "_step"] = Counter(first_time, Counter::kAvgIterations);
  state.counters[second + "_step"] = Counter(second_time, Counter::kAvgIterations);
  state.counters[first + "_vs_" + second] = second_time > 0 ? first_time / second_time : 0.0;
  for (const auto& [name, sums] :
       {std::pair<const std::string&, const Sums&>{first, first_sums}, {second, second_sums}}) {
    const std::string n(name);
    state.counters[n + "_bookkeeping"] = Counter(sums.times.bookkeeping, Counter::kAvgIterations);
    state.counters[n + "_solves"] = Counter(
        sums.times.local + sums.times.gather + sums.times.transfer + sums.times.global, Counter::kAvgIterations);
    state.counters[n + "_energy"] = Counter(sums.times.energy, Counter::kAvgIterations);
    state.counters[n + "_partner_steps"] = Counter(sums.partner_steps, Counter::kAvgIterations);
    state.counters[n + "_iterations"] = Counter(sums.iterations, Counter::kAvgIterations);
    state.counters[n + "_energy_passes"] = Counter(sums.energy_passes, Counter::kAvgIterations);
  }
  state.SetLabel(f.first->backendDescription());
}

// The landing cloth's global system with both blend factors (c = 1/h^2 and 4/h^2), and the
// weight of one contact pair at the default stiffness.
struct BlendFactoredCloth {
  Scene cloth = clothOnSphereAndGround();
  SceneData data{cloth};
  GlobalSystem system{data};
  double pair_weight = Collider{}.stiffness * cloth.masses[1000];
  BlendFactoredCloth() {
    const double h = 1.0 / 30.0;
    system.factor(1.0 / (h * h));
    system.factor(4.0 / (h * h));
  }
};

// One pair entering the contact set and one leaving (docs/method.md, "Contact"), each a rank-1
// update of the blend's two factors (c = 1/h^2 and 4/h^2); the simulator batches a step's
// changes into one rank-k update and one downdate per factor.
void runActiveSetUpdates(benchmark::State& state) {
  BlendFactoredCloth f;
  GlobalSystem& system = f.system;
  const double w = f.pair_weight;
  int vertex = 100;
  for (auto _ : state) {
    system.addToDiagonal(vertex, w);
    system.addToDiagonal(vertex, -w);
    vertex = vertex % 2400 + 37;
  }
  state.counters["update"] =
      benchmark::Counter(2.0 * state.iterations(), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel("rank-1 update of both blend factors");
}

// A contact set change of k pairs (docs/method.md, "Contact"): one batched rank-k update and
// its downdate of both blend factors (GlobalSystem::addToDiagonal), against a new assembly of L
// with both factorizations (the simulator's choice above kMaxContactUpdateColumns pairs). The
// counter is the time of one change.
void runContactSetChange(benchmark::State& state) {
  BlendFactoredCloth f;
  GlobalSystem& system = f.system;
  const int pairs = static_cast<int>(state.range(0));
  const double w = f.pair_weight;
  std::vector<int> vertices;
  for (int i = 0; i < pairs; ++i) vertices.push_back((i * 997) % f.cloth.numParticles());
  const std::vector<double> up(vertices.size(), w), down(vertices.size(), -w);
  for (auto _ : state) {
    if (pairs == 0) {
      system.assemble(f.data);
      system.refactorAll();
    } else {
      system.addToDiagonal(vertices, up);
      system.addToDiagonal(vertices, down);
    }
  }
  state.counters["change"] = benchmark::Counter((pairs == 0 ? 1.0 : 2.0) * state.iterations(),
                                                benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(pairs == 0 ? "assemble and refactor both blend factors" : "batched update of both blend factors");
}

}  // namespace

void registerContactCases() {
  // Self-contact's scaling: the crumpling cloth of 100 x 100 and 200 x 200 particles, on the CPU.
  for (const auto& [comparison, side] : {std::pair<const Comparison*, int>{&kSelfVsNone100, 100},
                                         std::pair<const Comparison*, int>{&kSelfVsNone200, 200}}) {
    for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend}) {
      const std::string name = "self_vs_none/cloth" + std::to_string(side) + "/" + integratorName(integrator) + "/cpu";
      benchmark::RegisterBenchmark(
          name.c_str(),
          [=](benchmark::State& state) { runContact(state, name, BackendChoice::Cpu, integrator, *comparison); })
          ->UseRealTime()
          ->Unit(benchmark::kMillisecond);
    }
  }
  benchmark::RegisterBenchmark("contact_set_change/cloth50", runContactSetChange)
      ->Arg(0)
      ->Arg(1)
      ->Arg(32)
      ->Arg(128)
      ->Arg(256)
      ->Arg(512)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("contact_active_set_updates/cloth50", runActiveSetUpdates)
      ->Unit(benchmark::kMicrosecond);
  for (const Comparison* comparison : {&kContactVsNone, &kMeshVsSphere, &kSelfVsNone}) {
    for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend}) {
      for (BackendChoice backend : allBackends()) {
        const std::string name = std::string(comparison->first_name) + "_vs_" + comparison->second_name + "/cloth50/" +
                                 integratorName(integrator) + "/" + backendLabel(backend);
        benchmark::RegisterBenchmark(
            name.c_str(), [=](benchmark::State& state) { runContact(state, name, backend, integrator, *comparison); })
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
      }
    }
  }
}

}  // namespace stabint::bench
