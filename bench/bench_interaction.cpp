// Per-frame input, grab and release against plain steps, interleaved in one run (the machine
// is noisy). Input: on the
// 50 x 50 cloth with BE, a scripted moving pin, the same motion given by setPinTarget every
// frame, and per-particle forces set every frame. The counters give each variant's mean step
// and its ratio to the scripted pin, the work the booking of a moving pin costs anyway.
#include "bench_common.hpp"

#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"

#include <chrono>
#include <cmath>
#include <exception>

namespace stabint::bench {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector3d handleOffset(double t) { return Eigen::Vector3d(0.05 * std::sin(2 * kPi * t), 0.0, 0.0); }

struct InputFixture {
  Scene scene, scripted_scene;
  std::unique_ptr<Simulator> scripted, pin_input, force_input;
  Eigen::MatrixX3d forces;
};

void runInput(benchmark::State& state, const std::string& key, BackendChoice backend) {
  if (const std::string why = skipReason(backend); !why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  InputFixture* fixture = nullptr;
  try {
    fixture = &cachedFixture<InputFixture>(key, [&] {
      auto f = std::make_unique<InputFixture>();
      f->scene = clothScene(50);
      f->scripted_scene = f->scene;
      f->scripted_scene.pins[0].target.amplitude = Eigen::Vector3d(0.05, 0.0, 0.0);  // = handleOffset(t)
      f->scripted_scene.pins[0].target.frequency = 1.0;
      const SimulatorOptions o = optionsFor(backend, Integrator::BackwardEuler);
      f->scripted = std::make_unique<Simulator>(f->scripted_scene, o);
      f->pin_input = std::make_unique<Simulator>(f->scene, o);
      f->force_input = std::make_unique<Simulator>(f->scene, o);
      f->forces = Eigen::MatrixX3d::Zero(f->scene.numParticles(), 3);
      for (Simulator* s : {f->scripted.get(), f->pin_input.get(), f->force_input.get()})
        for (int i = 0; i < 3; ++i) s->step();  // factorizations, first launches
      return f;
    });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  InputFixture& f = *fixture;
  const Eigen::Vector3d pin0 = f.scene.pins[0].target.position;
  const double h = f.pin_input->options().time_step;
  using Clock = std::chrono::steady_clock;
  auto timed = [](double& sum, auto&& body) {
    const auto start = Clock::now();
    body();
    sum += std::chrono::duration<double>(Clock::now() - start).count();
  };
  double scripted = 0, pin_input = 0, force_input = 0;
  try {
    for (auto _ : state) {
      timed(scripted, [&] { f.scripted->step(); });
      timed(pin_input, [&] {
        f.pin_input->setPinTarget(0, pin0 + handleOffset(f.pin_input->time() + h));
        f.pin_input->step();
      });
      timed(force_input, [&] {
        f.forces(7, 2) = 0.01 * std::sin(2 * kPi * (f.force_input->time() + h));
        f.force_input->setExternalForces(f.forces);
        f.force_input->step();
      });
    }
  } catch (const NonFiniteStateError& e) {
    state.SkipWithError(e.what());
    return;
  }
  using benchmark::Counter;
  setSizeCounters(state, f.scene);
  state.counters["scripted_pin_step"] = Counter(scripted, Counter::kAvgIterations);
  state.counters["pin_input_step"] = Counter(pin_input, Counter::kAvgIterations);
  state.counters["force_input_step"] = Counter(force_input, Counter::kAvgIterations);
  state.counters["pin_input_vs_scripted"] = scripted > 0 ? pin_input / scripted : 0.0;
  state.counters["force_input_vs_scripted"] = scripted > 0 ? force_input / scripted : 0.0;
  state.SetLabel(f.pin_input->backendDescription());
}

// Grab and release through the public API against plain steps, interleaved: per iteration one
// simulator grabs a vertex, steps, releases it and steps; its twin only steps twice. The
// counter `grab_release` is the extra time of the grab and the release together, relative to
// one plain step (issue 10: at most 0.2).
struct GrabFixture {
  std::unique_ptr<Simulator> grabbing, plain;
};

void runGrab(benchmark::State& state, const std::string& key, BackendChoice backend) {
  if (const std::string why = skipReason(backend); !why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  GrabFixture* fixture = nullptr;
  try {
    fixture = &cachedFixture<GrabFixture>(key, [&] {
      auto f = std::make_unique<GrabFixture>();
      const SimulatorOptions o = optionsFor(backend, Integrator::BackwardEuler);
      f->grabbing = std::make_unique<Simulator>(clothScene(50), o);
      f->plain = std::make_unique<Simulator>(clothScene(50), o);
      for (Simulator* s : {f->grabbing.get(), f->plain.get()})
        for (int i = 0; i < 3; ++i) s->step();
      return f;
    });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  GrabFixture& f = *fixture;
  using Clock = std::chrono::steady_clock;
  double grabbing = 0, plain = 0;
  int vertex = 1000;
  try {
    for (auto _ : state) {
      auto start = Clock::now();
      const int handle = f.grabbing->grab(vertex, 1e4);
      f.grabbing->step();
      f.grabbing->release(handle);
      f.grabbing->step();
      grabbing += std::chrono::duration<double>(Clock::now() - start).count();
      start = Clock::now();
      f.plain->step();
      f.plain->step();
      plain += std::chrono::duration<double>(Clock::now() - start).count();
      vertex = vertex % 2400 + 37;
    }
  } catch (const NonFiniteStateError& e) {
    state.SkipWithError(e.what());
    return;
  }
  using benchmark::Counter;
  state.counters["plain_step"] = Counter(plain / 2, Counter::kAvgIterations);
  state.counters["grab_release"] = plain > 0 ? (grabbing - plain) / (plain / 2) : 0.0;
  state.SetLabel(f.grabbing->backendDescription());
}

// The factor change alone: a pin's rank-1 update plus one solve, against dropping the factor and
// factoring cM + L again before that solve (GlobalSystem::addToDiagonal with `refactor`).
void runPinChange(benchmark::State& state, bool refactor) {
  const Scene cloth = clothScene(50);
  SceneData data(cloth);
  GlobalSystem system(data);
  const double c = 900.0;
  const Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Random(cloth.numParticles(), 3);
  Eigen::MatrixX3d x;
  system.solve(c, rhs, x);
  double sign = 1.0;
  for (auto _ : state) {
    system.addToDiagonal(1000, sign * 1e4, refactor);
    system.solve(c, rhs, x);
    benchmark::DoNotOptimize(x.data());
    sign = -sign;
  }
  state.SetLabel(refactor ? "refactorization" : "cholmod_updown");
}

// An element's stiffness change alone (Simulator::setElementStiffness): its rank-R update plus
// one solve, against refactoring. A spring of the 50 x 50 cloth (rank 1) and a tet of a
// 40 x 4 x 4 bar (3,264 particles; rank 3).
void runElementChange(benchmark::State& state, bool tets, bool refactor) {
  TetBarParams bar;
  bar.nx = 40;
  bar.ny = bar.nz = 4;
  const Scene scene = tets ? makeTetBar(bar) : clothScene(50);
  SceneData data(scene);
  GlobalSystem system(data);
  const double c = 900.0;
  const Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Random(scene.numParticles(), 3);
  Eigen::MatrixX3d x;
  system.solve(c, rhs, x);
  const ElementBlock& block = data.blocks()[tets ? 1 : 0];
  const ElementShape shape = block.type->shape();
  const int e = block.count / 2;
  const double* a = block.coefficients.data() + (shape.shared_coefficients ? 0 : shape.rows * shape.vertices * e);
  const double w = block.params[std::size_t(shape.params) * std::size_t(e)];
  double sign = 1.0;
  for (auto _ : state) {
    system.addElementTerm(&block.vertices[std::size_t(shape.vertices) * std::size_t(e)], shape.vertices, a, shape.rows,
                          sign * w,
                          refactor ? GlobalSystem::FactorChange::Drop : GlobalSystem::FactorChange::RankUpdate);
    system.solve(c, rhs, x);
    benchmark::DoNotOptimize(x.data());
    sign = -sign;
  }
  state.SetLabel(refactor ? "refactorization" : "cholmod_updown");
}

}  // namespace

void registerInteractionCases() {
  for (bool tets : {false, true}) {
    for (bool refactor : {false, true}) {
      const std::string name = std::string("element_change_and_solve/") + (tets ? "tetbar40/tet" : "cloth50/spring") +
                               "/" + (refactor ? "refactor" : "updown");
      benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& state) {
        runElementChange(state, tets, refactor);
      })->Unit(benchmark::kMicrosecond);
    }
  }
  for (BackendChoice backend : allBackends()) {
    const std::string name = std::string("grab_release_vs_step/cloth50/BE/") + backendLabel(backend);
    benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& state) { runGrab(state, name, backend); })
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond);
  }
  for (bool refactor : {false, true}) {
    const std::string name = std::string("pin_change_and_solve/cloth50/") + (refactor ? "refactor" : "updown");
    benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& state) {
      runPinChange(state, refactor);
    })->Unit(benchmark::kMicrosecond);
  }
  for (BackendChoice backend : allBackends()) {
    const std::string name = std::string("input_vs_scripted/cloth50/BE/") + backendLabel(backend);
    benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& state) { runInput(state, name, backend); })
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond);
  }
}

}  // namespace stabint::bench
