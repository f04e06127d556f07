// Why the host's CHOLMOD solve is slower with the OpenCL backend than with the CPU reference on
// the same scene (issue 11, item 2). The solve alone is timed (manual time), in the situations a
// local/global iteration puts it in:
//   host_solve/<scene>/<backend>/after_local  right after the local step's blocking read of the
//                                             right-hand side (as in every iteration)
//   host_solve/<scene>/<backend>/after_idle   the same, but 5 ms after that read, when the
//                                             OpenCL runtime's worker threads have gone idle
//   host_solve/<scene>/<backend>/repeated     the same solve again right after itself (the
//                                             factor hot in the cache, nothing in between)
// On the CPU reference the three differ only by what the local step leaves in the caches.
#include "bench_common.hpp"
#include "first_step.hpp"

#include <chrono>
#include <ctime>
#include <exception>
#include <thread>

namespace stabint::bench {
namespace {

using namespace first_step;

enum class When { AfterLocal, AfterIdle, Repeated };

double cpuSeconds(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

using HostSolveFixture = first_step::Fixture;

void runHostSolve(benchmark::State& state, const std::string& key, const std::function<Scene()>& make_scene,
                  BackendChoice choice, When when) {
  if (const std::string why = skipReason(choice); !why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  HostSolveFixture* fixture = nullptr;
  try {
    fixture =
        &cachedFixture<HostSolveFixture>(key, [&] { return std::make_unique<HostSolveFixture>(make_scene(), choice); });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  HostSolveFixture& f = *fixture;
  using Clock = std::chrono::steady_clock;
  double wall = 0.0, this_thread = 0.0, other_threads = 0.0;
  for (auto _ : state) {
    f.backend->localStepRhs(kX, kY, kC, kTimeStep, f.rhs);
    if (when == When::AfterIdle) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (when == When::Repeated) f.system.solve(kC, f.rhs, f.x);
    const double process_before = cpuSeconds(CLOCK_PROCESS_CPUTIME_ID);
    const double thread_before = cpuSeconds(CLOCK_THREAD_CPUTIME_ID);
    const auto start = Clock::now();
    f.system.solve(kC, f.rhs, f.x);
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    const double thread_cpu = cpuSeconds(CLOCK_THREAD_CPUTIME_ID) - thread_before;
    other_threads += cpuSeconds(CLOCK_PROCESS_CPUTIME_ID) - process_before - thread_cpu;
    this_thread += thread_cpu;
    wall += seconds;
    state.SetIterationTime(seconds);
  }
  // CPU time the solving thread got, and what the process's other threads (the OpenCL runtime's
  // workers) burnt meanwhile, per second of solve: a runtime that spins while the host solves
  // shows other_threads_cpu near 1 (a core) and this_thread_cpu below 1.
  state.counters["this_thread_cpu"] = wall > 0 ? this_thread / wall : 0.0;
  state.counters["other_threads_cpu"] = wall > 0 ? other_threads / wall : 0.0;
  state.SetLabel(f.backend->description());
}

}  // namespace

void registerHostSolveCases() {
  std::vector<SceneCase> scenes = referenceScenes();
  for (const SceneCase& scene : scenes)
    for (BackendChoice backend : allBackends())
      for (auto [when, label] : {std::pair{When::AfterLocal, "after_local"}, std::pair{When::AfterIdle, "after_idle"},
                                 std::pair{When::Repeated, "repeated"}}) {
        const std::string name = "host_solve/" + scene.name + "/" + backendLabel(backend) + "/" + label;
        const std::string key = "host_solve/" + scene.name + "/" + backendLabel(backend);
        benchmark::RegisterBenchmark(
            name.c_str(),
            [=, when = when](benchmark::State& state) { runHostSolve(state, key, scene.make, backend, when); })
            ->UseManualTime()
            ->Unit(benchmark::kMicrosecond);
      }
}

}  // namespace stabint::bench
