// One element pass of the CPU reference on one thread and on two, per scene and size: where a
// second thread starts to pay for a pass (the rule in host/cpu/threaded_pass.cpp, docs/method.md
// section 12). Case names:
//   thread_pass/<scene>/<pass>/threads:1           the pass on the calling thread
//   thread_pass/<scene>/<pass>/threads:2/<path>    on two threads, by the path:
//       auto      the library's choice (what a run gets)
//       buffered  forced: per-element results to buffers, gathered per vertex through the CSR
//       owned     forced: each thread owns a range of vertices and runs the elements on it
// <pass>: local (the local step with its right-hand side: plain PD's), local_energy (the same
// with the energy at x), gradient_energy (the force form with the objective's gradient and the
// energy at x: L-BFGS's local step) or energy (an energy pass: the blend's root finds).
// Scenes: spring cloths (structural, shear and bending springs) and triangle cloths (triangle
// strain and bending hinges) of 50 x 50 to 200 x 200 particles, tet bars of 192 to 23,814 tets;
// positions after 10 BE steps from rest (deformed, as in a run). Every path gives the same
// results bit for bit, so the variants of one scene time the same arithmetic. Counters:
// elements, threaded (1 when the pass took a threaded path), and the cost model's estimates on
// two threads (host/cpu/threaded_pass.cpp): est_serial_us, est_owned_us, est_buffered_us.
//   thread_pass_wake/threads:2                      one parallelFor of two tasks, each waiting until
//                                                   both have started: a worker's wake-up
//   thread_pass_sum/<chunks|chain>                  a sum of 100,000 stored energies, per element:
//                                                   the passes' rule (sumEnergies) or one chain
//   thread_pass_kind/<scene>/<kind>                 one block's pass alone on one thread (the
//                                                   local step's flags): its ns_per_element
//                                                   beside the kind's declared_ns (kElementNs)
#include "bench_common.hpp"
#include "first_step.hpp"

#include "cpu/cpu_backend.hpp"
#include "common/worker_pool.hpp"
#include "elements/element_type.hpp"
#include "elements/energy_sum.hpp"

#include <array>
#include <atomic>
#include <chrono>
#include <exception>
#include <map>

namespace stabint::bench {
namespace {

using namespace first_step;

std::vector<SceneCase> passScenes() {
  std::vector<SceneCase> scenes;
  for (ClothModel model : {ClothModel::Springs, ClothModel::Triangles})
    for (int side : {50, 100, 200}) scenes.push_back(clothCase(model, side));
  for (const std::array<int, 3>& cells :
       {std::array<int, 3>{8, 2, 2}, std::array<int, 3>{12, 3, 3}, std::array<int, 3>{16, 4, 4},
        std::array<int, 3>{25, 5, 5}, std::array<int, 3>{49, 9, 9}})
    scenes.push_back(tetBarCase(cells[0], cells[1], cells[2]));
  return scenes;
}

struct PassFixture {
  explicit PassFixture(const Scene& s) : scene(s), data(scene), backend(makeCpuBackend(data, forcing, kSlots)) {
    Simulator sim(scene, optionsFor(BackendChoice::Cpu, Integrator::BackwardEuler));
    for (int i = 0; i < 10; ++i) sim.step();
    Eigen::MatrixX3d y = sim.positions() + kTimeStep * sim.velocities();
    backend->write(kX, sim.positions());
    backend->write(kY, y);
  }
  Scene scene;
  SceneData data;
  Forcing forcing{data.scene()};
  std::unique_ptr<Backend> backend;
  Eigen::MatrixX3d rhs;
};

// Every scene's fixture is kept (CPU only, at most some tens of MB each), so that interleaved
// cases do not rebuild them.
PassFixture* passFixture(benchmark::State& state, const SceneCase& scene) {
  static std::map<std::string, std::unique_ptr<PassFixture>> fixtures;
  static const bool registered = (registerFixtureRelease([] { fixtures.clear(); }), true);
  (void)registered;
  try {
    std::unique_ptr<PassFixture>& f = fixtures[scene.name];
    if (!f) f = std::make_unique<PassFixture>(scene.make());
    return f.get();
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return nullptr;
  }
}

enum class Pass { Local, LocalEnergy, GradientEnergy, Energy };

class PathFor {
 public:
  explicit PathFor(ThreadedPassPath path) : previous_(threadedPassPath()) { setThreadedPassPath(path); }
  ~PathFor() { setThreadedPassPath(previous_); }
  PathFor(const PathFor&) = delete;
  PathFor& operator=(const PathFor&) = delete;

 private:
  ThreadedPassPath previous_;
};

void runPass(benchmark::State& state, const SceneCase& scene, Pass pass, int threads, ThreadedPassPath path) {
  PassFixture* f = passFixture(state, scene);
  if (!f) return;
  ThreadsFor setting(threads);
  PathFor forced(path);
  PotentialEnergy e;
  for (auto _ : state) {
    switch (pass) {
      case Pass::Local: f->backend->localStepRhs(kX, kY, kC, kTimeStep, f->rhs, nullptr); break;
      case Pass::LocalEnergy: f->backend->localStepRhs(kX, kY, kC, kTimeStep, f->rhs, &e); break;
      case Pass::GradientEnergy: f->backend->localStepGradient(kX, kY, kC, kTimeStep, f->rhs, &e); break;
      case Pass::Energy: e = f->backend->potential(kX, kTimeStep); break;
    }
    benchmark::DoNotOptimize(f->rhs.data());
    benchmark::DoNotOptimize(e);
  }
  state.counters["elements"] = elementCount(f->scene);
  state.counters["threaded"] = lastPassPath() == ThreadedPassPath::Serial ? 0 : 1;
  const int flags = pass == Pass::Local            ? kPassProjection
                    : pass == Pass::LocalEnergy    ? kPassProjection | kPassEnergy
                    : pass == Pass::GradientEnergy ? kPassForce | kPassEnergy
                                                   : kPassEnergy;
  const ThreadedPassEstimate est = estimateThreadedPass(f->data, flags, 2);
  state.counters["est_serial_us"] = 1e6 * est.serial;
  state.counters["est_owned_us"] = 1e6 * est.owned;
  state.counters["est_buffered_us"] = 1e6 * est.buffered;
}

// One block's pass alone on the calling thread (ElementType::pass with the local step's flags):
// the cost per element that the kind declares (Kind::kElementNs), as counter ns_per_element.
void runBlock(benchmark::State& state, const SceneCase& scene, const std::string& kind) {
  PassFixture* f = passFixture(state, scene);
  if (!f) return;
  const ElementBlock* block = nullptr;
  for (const ElementBlock& b : f->data.blocks())
    if (b.type->identifier() == kind) block = &b;
  if (!block || block->count == 0) {
    state.SkipWithError(("no " + kind + " in " + scene.name).c_str());
    return;
  }
  Eigen::MatrixX3d x, out;
  f->backend->read(kX, x);
  out.setZero(x.rows(), 3);
  double energy = 0.0;
  for (auto _ : state) {
    energy += block->type->pass(*block, block->params, x, kPassProjection, &out);
    benchmark::DoNotOptimize(out.data());
  }
  benchmark::DoNotOptimize(energy);
  state.counters["elements"] = block->count;
  state.counters["ns_per_element"] = benchmark::Counter(
      double(block->count), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["declared_ns"] = block->type->elementCost();
}

// One parallelFor of two tasks on two threads, each waiting (up to 1 ms) until both have started:
// what waking the worker and waiting for it costs a threaded pass (once per pass on the Owned
// path, twice on the Buffered one). An empty task would not measure it: the calling thread takes
// both before the worker is up.
void runWake(benchmark::State& state) {
  ThreadsFor setting(2);
  for (auto _ : state) {
    std::atomic<int> started{0};
    parallelFor(2, [&](int) {
      started.fetch_add(1);
      const auto start = std::chrono::steady_clock::now();
      while (started.load() < 2 && std::chrono::steady_clock::now() - start < std::chrono::milliseconds(1)) {
      }
    });
  }
}

// The calling thread's sum of a block's stored element energies after a threaded pass: by the
// passes' rule (sumEnergies, chunks side by side) or, for comparison, as one chain of dependent
// additions in element order (the rule before): per element, counter ns_per_element.
void runSum(benchmark::State& state, bool chunks) {
  std::vector<double> energies(100'000);
  for (std::size_t i = 0; i < energies.size(); ++i) energies[i] = 1.0 + 1e-6 * double(i % 1000);
  for (auto _ : state) {
    double sum = 0.0;
    if (chunks) {
      sum = sumEnergies(energies.data(), static_cast<int>(energies.size()));
    } else {
      for (double e : energies) sum += e;
    }
    benchmark::DoNotOptimize(sum);
  }
  state.counters["ns_per_element"] = benchmark::Counter(
      double(energies.size()), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

}  // namespace

void registerThreadPassCases() {
  benchmark::RegisterBenchmark("thread_pass_sum/chunks", runSum, true)->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("thread_pass_sum/chain", runSum, false)->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("thread_pass_wake/threads:2", runWake)->UseRealTime()->Unit(benchmark::kMicrosecond);
  for (const SceneCase& scene : passScenes())
    for (auto [pass, label] : {std::pair{Pass::Local, "local"}, std::pair{Pass::LocalEnergy, "local_energy"},
                               std::pair{Pass::GradientEnergy, "gradient_energy"}, std::pair{Pass::Energy, "energy"}}) {
      const std::string base = "thread_pass/" + scene.name + "/" + label;
      auto add = [&](const std::string& name, int threads, ThreadedPassPath path) {
        benchmark::RegisterBenchmark(
            name.c_str(), [=, p = pass](benchmark::State& state) { runPass(state, scene, p, threads, path); })
            ->UseRealTime()
            ->Unit(benchmark::kMicrosecond);
      };
      add(base + "/threads:1", 1, ThreadedPassPath::Auto);
      add(base + "/threads:2/auto", 2, ThreadedPassPath::Auto);
      add(base + "/threads:2/buffered", 2, ThreadedPassPath::Buffered);
      add(base + "/threads:2/owned", 2, ThreadedPassPath::Owned);
    }
  std::vector<SceneCase> scenes = passScenes();
  scenes.push_back({"pinned100x100", [] {
                      ClothGridParams p;
                      p.nx = p.ny = 100;
                      for (int i = 0; i < p.nx * p.ny; ++i) p.pinned.push_back(i);
                      return makeClothGrid(p);
                    }});
  for (auto [scene_index, kind] : {std::pair{2, "spring"}, std::pair{5, "triangle_strain"},
                                   std::pair{5, "bending_hinge"}, std::pair{10, "tet"}, std::pair{11, "pin"}}) {
    const SceneCase scene = scenes[size_t(scene_index)];
    const std::string identifier = kind;
    auto run = [scene, identifier](benchmark::State& state) { runBlock(state, scene, identifier); };
    benchmark::RegisterBenchmark(("thread_pass_kind/" + scene.name + "/" + identifier).c_str(), run)
        ->Unit(benchmark::kMicrosecond);
  }
}

}  // namespace stabint::bench
