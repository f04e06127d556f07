#pragma once
// Shared pieces of the benchmark suite: the benchmark scenes, backend choices, a per-case fixture
// cache (so that Google Benchmark's repeated calls of one case pay the set-up once) and the
// counters every case reports.
#include <stabint/stabint.hpp>

#include <benchmark/benchmark.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace stabint::bench {

/// Backends a case runs on. The two OpenCL precisions are separate cases.
enum class BackendChoice { Cpu, OpenCLDouble, OpenCLFloat };
const std::vector<BackendChoice>& allBackends();
const char* backendLabel(BackendChoice choice);  // "cpu", "opencl-double", "opencl-float"
/// Why the case cannot run here ("" when it can): no OpenCL device, or no fp64 for double.
std::string skipReason(BackendChoice choice);
/// Default SimulatorOptions (10 iterations, be_iterations default) on the chosen backend.
SimulatorOptions optionsFor(BackendChoice choice, Integrator integrator);

/// A named benchmark scene.
struct SceneCase {
  std::string name;
  std::function<Scene()> make;
};
/// The two reference scenes: cloth 50x50 (2,500 particles) and the tet bar 50x10x10 vertices
/// (5,000 particles).
const std::vector<SceneCase>& referenceScenes();
Scene clothScene(int side);
/// The main job's violent scenes (stabint-study motion): the 20 x 20 cloth falling from 30
/// degrees below the horizontal about its pinned top corners, and the stiff chain pendulum
/// released horizontally at rest. The blend takes every branch on them.
const std::vector<SceneCase>& violentScenes();

/// Side lengths of the cloth scaling family, 10x10 up to 224x224 (50,176 particles). With
/// STABINT_BENCH_QUICK set, only up to 71x71.
std::vector<int> scalingSides();
bool quickMode();

/// The scenes behind BackendKind::Auto's rule (docs/method.md "Backend choice"): spring cloths
/// ("springs<side>"), triangle cloths ("triangles<side>", ClothModel::Triangles) from 20x20 to
/// 100x100 particles and tet bars ("tetbar<cells>") from 8x2x2 to 80x16x16 cells (192 to 122,880
/// tets). With STABINT_BENCH_QUICK set, only up to 50x50 and 35x7x7.
std::vector<SceneCase> autoRuleScenes();
/// "springs<side>x<side>" or "triangles<side>x<side>": makeClothGrid's cloth of that model.
SceneCase clothCase(ClothModel model, int side);
/// "tetbar<nx>x<ny>x<nz>": makeTetBar's bar of that many cells.
SceneCase tetBarCase(int nx, int ny, int nz);

void registerFixtureRelease(std::function<void()> release);
/// Drops every cached fixture (called before building a new one and at the end of main, while
/// the OpenCL runtime is still loaded).
void releaseAllFixtures();

/// Sets the process's CPU thread count (common/worker_pool.hpp) for one case and puts the previous
/// one back.
class ThreadsFor {
 public:
  explicit ThreadsFor(int threads);
  ~ThreadsFor();
  ThreadsFor(const ThreadsFor&) = delete;
  ThreadsFor& operator=(const ThreadsFor&) = delete;

 private:
  int previous_;
};

/// Keeps the fixture of the case that ran last: Google Benchmark calls a case's function several
/// times (growing iteration counts); the fixture (simulator, backend, factors) is built once.
/// A different key drops the previous fixture first, so only one lives at a time.
template <class T>
T& cachedFixture(const std::string& key, const std::function<std::unique_ptr<T>()>& make) {
  struct Slot {
    std::string key;
    std::unique_ptr<T> value;
  };
  static Slot slot;
  static const bool registered = (registerFixtureRelease([] {
                                    slot.value.reset();
                                    slot.key.clear();
                                  }),
                                  true);
  (void)registered;
  if (!slot.value || slot.key != key) {
    releaseAllFixtures();  // at most one fixture (of any type) alive: the scaling cases are large
    slot.value = make();
    slot.key = key;
  }
  return *slot.value;
}

/// Sets the per-phase counters (seconds per benchmark iteration, averaged): local, gather,
/// transfer, global, energy, bookkeeping; and the phase sum.
void setPhaseCounters(benchmark::State& state, const PhaseTimes& summed);
/// particles and elements of the scene (constant counters).
void setSizeCounters(benchmark::State& state, const Scene& scene);

}  // namespace stabint::bench

namespace stabint::bench {
// Case registration, one function per file.
void registerStepCases();         // bench_steps.cpp
void registerIterationCases();    // bench_iterations.cpp
void registerSolverCases();       // bench_solver.cpp
void registerInteractionCases();  // bench_interaction.cpp
void registerContactCases();      // bench_contact.cpp
void registerHostSolveCases();    // bench_host_solve.cpp
void registerBatchCases();        // bench_batch.cpp
void registerFrameCases();        // bench_frame.cpp
void registerThreadPassCases();   // bench_thread_pass.cpp
void registerConvergenceCases();  // bench_convergence.cpp
}  // namespace stabint::bench
