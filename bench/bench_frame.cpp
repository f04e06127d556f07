// The tet bar's frame on the CPU's threads (issue 11's headline: a blend frame of the 50 x 10 x 10
// tet bar at 10 iterations in at most 33 ms). Each case runs with a thread count set for the
// process (setCpuThreads, restored afterwards); the thread count changes no result, so the
// variants of one scene time the same motion:
//   frame/<scene>/<integrator>/<backend>/threads:N   Simulator::step(), 30 steps per repetition
//                                                    from the same checkpoint
//   frame_pass/<scene>/<local|energy>/threads:N      one element pass of the CPU reference: the
//                                                    local step with its right-hand side, or an
//                                                    energy pass
//   frame_solve/<scene>/<one_solve|library>/threads:N
//                                                    the host's solve of K_c x = rhs alone (manual
//                                                    time, after a local step): Eigen's one
//                                                    CHOLMOD solve of the three columns, or
//                                                    GlobalSystem::solve (one pass over the factor
//                                                    on the calling thread; it was two column
//                                                    groups on two threads, "column_groups")
#include "bench_common.hpp"
#include "first_step.hpp"

#include "cpu/worker_pool.hpp"

#include <Eigen/CholmodSupport>

#include <chrono>
#include <exception>

namespace stabint::bench {
namespace {

using namespace first_step;
constexpr int kFrameSteps = 30;

// Sets the process's thread count for one case and puts the previous one back.
class ThreadsFor {
 public:
  explicit ThreadsFor(int threads) : previous_(cpuThreads()) { setCpuThreads(threads); }
  ~ThreadsFor() { setCpuThreads(previous_); }
  ThreadsFor(const ThreadsFor&) = delete;
  ThreadsFor& operator=(const ThreadsFor&) = delete;

 private:
  int previous_;
};

const SceneCase& tetBar() {
  for (const SceneCase& scene : referenceScenes())
    if (scene.name == "tetbar50x10x10") return scene;
  throw std::logic_error("no tetbar50x10x10 among the reference scenes");
}

struct FrameFixture {
  Scene scene;
  std::unique_ptr<Simulator> sim;
  Checkpoint start;
};

void runFrame(benchmark::State& state, const std::string& key, BackendChoice backend, Integrator integrator,
              int threads) {
  if (const std::string why = skipReason(backend); !why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  ThreadsFor setting(threads);
  FrameFixture* fixture = nullptr;
  try {
    fixture = &cachedFixture<FrameFixture>(key, [&] {
      auto f = std::make_unique<FrameFixture>();
      f->scene = tetBar().make();
      f->sim = std::make_unique<Simulator>(f->scene, optionsFor(backend, integrator));
      // Past the first steps' factorizations (the blend's BE factor comes with its first BE
      // branch) and kernel builds.
      for (int i = 0; i < 10; ++i) f->sim->step();
      f->start = f->sim->checkpoint();
      return f;
    });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  FrameFixture& f = *fixture;
  f.sim->restore(f.start);
  PhaseTimes summed;
  double iterations = 0, energy_evaluations = 0;
  for (auto _ : state) {
    const StepReport& r = f.sim->step();
    summed += r.times;
    iterations += r.iterations;
    energy_evaluations += r.energy_evaluations;
  }
  using benchmark::Counter;
  setSizeCounters(state, f.scene);
  setPhaseCounters(state, summed);
  state.counters["iterations"] = Counter(iterations, Counter::kAvgIterations);
  state.counters["energy_evaluations"] = Counter(energy_evaluations, Counter::kAvgIterations);
  state.counters["threads"] = threads;
  state.SetLabel(f.sim->backendDescription());
}

// The first-step fixture with CHOLMOD's own solve of the three columns beside the library's.
struct PassFixture : Fixture {
  explicit PassFixture(const Scene& s) : Fixture(s, BackendChoice::Cpu) {
    // CHOLMOD's solve through Eigen: one cholmod_solve of the three columns.
    Eigen::SparseMatrix<double> k = system.stiffnessLaplacian();
    for (Eigen::Index j = 0; j < k.rows(); ++j) k.coeffRef(j, j) += kC * system.masses()[j];
    one_solve.compute(k);
  }
  Eigen::CholmodSimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> one_solve;
};

PassFixture* passFixture(benchmark::State& state) {
  try {
    return &cachedFixture<PassFixture>("frame_pass", [] { return std::make_unique<PassFixture>(tetBar().make()); });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return nullptr;
  }
}

void runPass(benchmark::State& state, bool energy_only, int threads) {
  ThreadsFor setting(threads);
  PassFixture* f = passFixture(state);
  if (!f) return;
  for (auto _ : state) {
    if (energy_only) {
      benchmark::DoNotOptimize(f->backend->potential(kX, kTimeStep));
    } else {
      f->backend->localStepRhs(kX, kY, kC, kTimeStep, f->rhs);
      benchmark::DoNotOptimize(f->rhs.data());
    }
  }
  state.counters["threads"] = threads;
}

void runSolve(benchmark::State& state, bool library, int threads) {
  ThreadsFor setting(threads);
  PassFixture* f = passFixture(state);
  if (!f) return;
  using Clock = std::chrono::steady_clock;
  for (auto _ : state) {
    f->backend->localStepRhs(kX, kY, kC, kTimeStep, f->rhs);  // what precedes a solve in a step
    const auto start = Clock::now();
    if (library) {
      f->system.solve(kC, f->rhs, f->x);
    } else {
      f->x = f->one_solve.solve(f->rhs);
    }
    state.SetIterationTime(std::chrono::duration<double>(Clock::now() - start).count());
  }
  state.counters["threads"] = threads;
}

}  // namespace

void registerFrameCases() {
  const std::string scene = tetBar().name;
  for (Integrator integrator : {Integrator::EnergyBlend, Integrator::BackwardEuler})
    for (BackendChoice backend : allBackends())
      for (int threads : {1, 2}) {
        const std::string base = "frame/" + scene + "/" + integratorName(integrator) + "/" + backendLabel(backend);
        const std::string name = base + "/threads:" + std::to_string(threads);
        benchmark::RegisterBenchmark(
            name.c_str(), [=](benchmark::State& state) { runFrame(state, base, backend, integrator, threads); })
            ->Iterations(kFrameSteps)
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
      }
  for (int threads : {1, 2}) {
    const std::string suffix = "/threads:" + std::to_string(threads);
    for (auto [energy_only, label] : {std::pair{false, "local"}, std::pair{true, "energy"}})
      benchmark::RegisterBenchmark(
          ("frame_pass/" + scene + "/" + label + suffix).c_str(),
          [=, energy = energy_only](benchmark::State& state) { runPass(state, energy, threads); })
          ->UseRealTime()
          ->Unit(benchmark::kMicrosecond);
    for (auto [library, label] : {std::pair{false, "one_solve"}, std::pair{true, "library"}})
      benchmark::RegisterBenchmark(("frame_solve/" + scene + "/" + label + suffix).c_str(),
                                   [=, ours = library](benchmark::State& state) { runSolve(state, ours, threads); })
          ->UseManualTime()
          ->Unit(benchmark::kMicrosecond);
  }
}

}  // namespace stabint::bench
