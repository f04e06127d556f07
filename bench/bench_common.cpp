#include "bench_common.hpp"

#include "common/worker_pool.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>

namespace stabint::bench {

ThreadsFor::ThreadsFor(int threads) : previous_(cpuThreads()) { setCpuThreads(threads); }
ThreadsFor::~ThreadsFor() { setCpuThreads(previous_); }

const std::vector<BackendChoice>& allBackends() {
  static const std::vector<BackendChoice> all{BackendChoice::Cpu, BackendChoice::OpenCLDouble,
                                              BackendChoice::OpenCLFloat};
  return all;
}

const char* backendLabel(BackendChoice choice) {
  switch (choice) {
    case BackendChoice::Cpu: return "cpu";
    case BackendChoice::OpenCLDouble: return "opencl-double";
    case BackendChoice::OpenCLFloat: return "opencl-float";
  }
  return "?";
}

std::string skipReason(BackendChoice choice) {
  if (choice == BackendChoice::Cpu) return "";
  static const std::vector<OpenCLDeviceInfo> devices = listOpenCLDevices();
  if (devices.empty()) return "skipped: no OpenCL platform/device available";
  if (choice == BackendChoice::OpenCLDouble &&
      std::none_of(devices.begin(), devices.end(), [](const OpenCLDeviceInfo& d) { return d.fp64; }))
    return "skipped: no OpenCL device with cl_khr_fp64";
  return "";
}

SimulatorOptions optionsFor(BackendChoice choice, Integrator integrator) {
  SimulatorOptions o;
  o.integrator = integrator;
  o.backend = choice == BackendChoice::Cpu ? BackendKind::CpuReference : BackendKind::OpenCL;
  o.opencl.precision = choice == BackendChoice::OpenCLFloat ? Precision::Float : Precision::Double;
  return o;
}

Scene clothScene(int side) {
  ClothGridParams p;
  p.nx = side;
  p.ny = side;
  return makeClothGrid(p);
}

const std::vector<SceneCase>& referenceScenes() {
  static const std::vector<SceneCase> scenes{
      {"cloth50x50", [] { return clothScene(50); }},
      {"tetbar50x10x10",
       [] {
         TetBarParams p;
         p.nx = 49;  // cells: (49+1) x (9+1) x (9+1) = 5,000 particles
         p.ny = 9;
         p.nz = 9;
         return makeTetBar(p);
       }},
  };
  return scenes;
}

const std::vector<SceneCase>& violentScenes() {
  static const std::vector<SceneCase> scenes{
      {"fallingcloth20x20",
       [] {
         // As the study's falling cloth (tools/study/study_scenes.cpp): tilted about its pinned top
         // edge to 30 degrees below the horizontal, at rest in that shape.
         ClothGridParams p;
         Scene s = makeClothGrid(p);
         const double tilt = 30.0 * M_PI / 180.0;
         for (int r = 0; r < s.numParticles(); ++r) {
           const double along = p.height - s.positions(r, 1);
           s.positions.row(r) << s.positions(r, 0), -along * std::sin(tilt), along * std::cos(tilt);
         }
         s.rest_positions = s.positions;
         for (Pin& pin : s.pins) pin.target.position = s.positions.row(pin.vertex).transpose();
         return s;
       }},
      {"chain", [] { return makeChainPendulum(); }},
  };
  return scenes;
}

bool quickMode() {
  const char* v = std::getenv("STABINT_BENCH_QUICK");
  return v != nullptr && *v != '\0' && std::string(v) != "0";
}

std::vector<int> scalingSides() {
  std::vector<int> sides{10, 16, 25, 35, 50, 71, 100, 141, 180, 224};
  if (quickMode()) sides.erase(std::remove_if(sides.begin(), sides.end(), [](int s) { return s > 71; }), sides.end());
  return sides;
}

std::vector<SceneCase> autoRuleScenes() {
  std::vector<SceneCase> scenes;
  const std::vector<int> sides = quickMode() ? std::vector<int>{20, 35, 50} : std::vector<int>{20, 35, 50, 71, 100};
  for (ClothModel model : {ClothModel::Springs, ClothModel::Triangles})
    for (int side : sides) {
      scenes.push_back(clothCase(model, side));
    }
  std::vector<std::array<int, 3>> bars{{8, 2, 2}, {16, 4, 4}, {25, 5, 5}, {35, 7, 7}, {49, 9, 9}, {80, 16, 16}};
  if (quickMode()) bars.resize(4);
  for (const auto& cells : bars) scenes.push_back(tetBarCase(cells[0], cells[1], cells[2]));
  return scenes;
}

SceneCase clothCase(ClothModel model, int side) {
  const std::string size = std::to_string(side) + "x" + std::to_string(side);
  return {(model == ClothModel::Springs ? "springs" : "triangles") + size, [side, model] {
            ClothGridParams p;
            p.nx = p.ny = side;
            p.model = model;
            return makeClothGrid(p);
          }};
}

SceneCase tetBarCase(int nx, int ny, int nz) {
  return {"tetbar" + std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz), [nx, ny, nz] {
            TetBarParams p;
            p.nx = nx;
            p.ny = ny;
            p.nz = nz;
            return makeTetBar(p);
          }};
}

namespace {
std::vector<std::function<void()>>& releases() {
  static std::vector<std::function<void()>> r;
  return r;
}
}  // namespace

void registerFixtureRelease(std::function<void()> release) { releases().push_back(std::move(release)); }

void releaseAllFixtures() {
  for (auto& release : releases()) release();
}

void setPhaseCounters(benchmark::State& state, const PhaseTimes& t) {
  using benchmark::Counter;
  state.counters["local"] = Counter(t.local, Counter::kAvgIterations);
  state.counters["gather"] = Counter(t.gather, Counter::kAvgIterations);
  state.counters["transfer"] = Counter(t.transfer, Counter::kAvgIterations);
  state.counters["global"] = Counter(t.global, Counter::kAvgIterations);
  state.counters["energy"] = Counter(t.energy, Counter::kAvgIterations);
  state.counters["bookkeeping"] = Counter(t.bookkeeping, Counter::kAvgIterations);
  state.counters["phases"] = Counter(t.total(), Counter::kAvgIterations);
}

void setSizeCounters(benchmark::State& state, const Scene& scene) {
  state.counters["particles"] = scene.numParticles();
  state.counters["elements"] = stabint::elementCount(scene);
}

}  // namespace stabint::bench
