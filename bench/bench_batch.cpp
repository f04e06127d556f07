// batch/<scene>/<integrator>/<backend>/<variant>/scenes:N: N small scenes advanced one step each,
// either as one BatchSimulator (variant "batch": one solve and one factor for all, one launch per
// phase on OpenCL) or as N Simulators one after another ("separate"), with BackwardEuler ("BE") or
// the blend ("blend", EnergyBlend at the default iterations). The ratio of the two is the batch's
// gain (docs/benchmarks.md, "Many scenes at once").
// bench/batch_chart.py draws and tabulates a run of the family. batch_stops/: solves stopped by
// accuracy, per scene (runBatchStops).
#include "bench_common.hpp"

#include "driver/batch_simulator.hpp"

#include <chrono>
#include <cmath>
#include <tuple>

namespace stabint::bench {
namespace {

struct BatchFixture {
  std::unique_ptr<BatchSimulator> batch;
  std::vector<Simulator> separate;
};

// A fresh fixture per case function call (every repetition times the same steps from rest), made
// by `make`; null, with the case skipped, where the backend is missing.
BatchFixture* freshFixture(benchmark::State& state, const std::string& name, BackendChoice backend,
                           const std::function<std::unique_ptr<BatchFixture>()>& make) {
  if (const std::string why = skipReason(backend); !why.empty()) {
    state.SkipWithError(why.c_str());
    return nullptr;
  }
  releaseAllFixtures();
  return &cachedFixture<BatchFixture>(name, make);
}

void runBatch(benchmark::State& state, const std::string& name, const std::function<Scene()>& make,
              BackendChoice backend, Integrator integrator, bool batched) {
  const int count = static_cast<int>(state.range(0));
  BatchFixture* fixture_or_null = freshFixture(state, name, backend, [&] {
    auto fixture = std::make_unique<BatchFixture>();
    const std::vector<Scene> scenes(static_cast<std::size_t>(count), make());
    const SimulatorOptions options = optionsFor(backend, integrator);
    if (batched) {
      fixture->batch = std::make_unique<BatchSimulator>(scenes, options);
    } else {
      fixture->separate.reserve(scenes.size());
      for (const Scene& s : scenes) fixture->separate.emplace_back(s, options);
    }
    return fixture;
  });
  if (!fixture_or_null) return;
  BatchFixture& f = *fixture_or_null;
  // The share of scene-steps whose IM candidate the blend accepted (the others need the BE partner,
  // which the batch then solves for every scene): the two variants must take the same branches
  // for their times to compare.
  int im_steps = 0;
  auto count_branch = [&](const StepReport& r) { im_steps += r.branch == BlendBranch::ImplicitMidpoint; };
  PhaseTimes summed;  // the batch's phases per step (where a batch's step goes: device or host)
  for (auto _ : state) {
    if (batched) {
      const BatchStepReport& r = f.batch->step();
      summed += r.times;
      for (const StepReport& scene : r.scenes) count_branch(scene);
    } else {
      for (Simulator& s : f.separate) count_branch(s.step());
    }
  }
  if (batched) setPhaseCounters(state, summed);
  state.counters["scenes"] = count;
  if (integrator == Integrator::EnergyBlend)
    state.counters["im_fraction"] = double(im_steps) / (double(count) * double(state.iterations()));
  state.SetLabel(batched ? "one BatchSimulator" : "one Simulator per scene");
}

// What runBatchInput gives every scene each frame.
enum class BatchInput { Forces, State, States, Stiffness };

const char* inputLabel(BatchInput input) {
  switch (input) {
    case BatchInput::Forces: return "forces";
    case BatchInput::State: return "state";
    case BatchInput::States: return "states";
    case BatchInput::Stiffness: return "stiffness";
  }
  return "";
}

// Per-frame input to every scene of a batch: each frame sets every scene's external forces
// ("forces"), state ("state": its positions and velocities as they are, an event of zero
// energy) or its first spring's stiffness ("stiffness": 1% up and down in turn, an element
// change: an event, an update of the factor), one call per scene, or every scene's state in one
// setStates call ("states"), timed, then steps the batch (not timed). What one frame's input
// costs a game driving many bodies; per scene it must not grow with the batch.
void runBatchInput(benchmark::State& state, const std::string& name, const std::function<Scene()>& make,
                   BackendChoice backend, BatchInput input) {
  const int count = static_cast<int>(state.range(0));
  BatchFixture* f = freshFixture(state, name, backend, [&] {
    auto fixture = std::make_unique<BatchFixture>();
    fixture->batch = std::make_unique<BatchSimulator>(std::vector<Scene>(std::size_t(count), make()),
                                                      optionsFor(backend, Integrator::BackwardEuler));
    return fixture;
  });
  if (!f) return;
  BatchSimulator& batch = *f->batch;
  const Eigen::MatrixX3d forces = Eigen::MatrixX3d::Constant(batch.numParticles(0), 3, 0.01);
  const double stiffness = make().springs.at(0).stiffness;
  int frame = 0;
  double seconds = 0.0;
  std::vector<Eigen::MatrixX3d> x(static_cast<std::size_t>(count)), v(static_cast<std::size_t>(count));
  std::vector<int> all(static_cast<std::size_t>(count));
  for (int s = 0; s < count; ++s) all[std::size_t(s)] = s;
  for (auto _ : state) {
    if (input == BatchInput::State || input == BatchInput::States) {
      for (int s = 0; s < count; ++s) {
        x[std::size_t(s)] = batch.positions(s);
        v[std::size_t(s)] = batch.velocities(s);
      }
    }
    const auto start = std::chrono::steady_clock::now();
    const double k = stiffness * (frame++ % 2 == 0 ? 1.01 : 1.0);
    if (input == BatchInput::States) batch.setStates(all, x, v);
    for (int s = 0; s < count && input != BatchInput::States; ++s) {
      if (input == BatchInput::Forces)
        batch.setExternalForces(s, forces);
      else if (input == BatchInput::State)
        batch.setState(s, x[std::size_t(s)], v[std::size_t(s)]);
      else
        batch.setElementStiffness(s, ElementKind::Spring, 0, k);
    }
    // Element changes book their events when something reads them (here H*) or at the step: the
    // time counted includes that.
    if (input == BatchInput::Stiffness) benchmark::DoNotOptimize(batch.target(count - 1));
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.PauseTiming();
    batch.step();
    state.ResumeTiming();
  }
  state.counters["scenes"] = count;
  state.counters["us_per_scene"] = 1e6 * seconds / (double(state.iterations()) * count);
}

// A batch whose scenes stop their solves by accuracy, each on its own (docs/method.md section 11):
// `count` 10 x 10 cloths whose stretch stiffnesses span 1e2 to 1e4 N/m (so they stop at different
// counts), BE with every solve to a tolerance (1e-6 of the objective's change; for "lbfgs-gradient"
// L-BFGS's gradient_tolerance 1e-2), at most 60 iterations, 20 steps from rest. Counter
// `iterations`: the mean over the scenes and steps.
void runBatchStops(benchmark::State& state, const std::string& name, BackendChoice backend, Acceleration acceleration,
                   bool gradient_stop) {
  const int count = static_cast<int>(state.range(0));
  BatchFixture* f = freshFixture(state, name, backend, [&] {
    std::vector<Scene> scenes;
    for (int s = 0; s < count; ++s) {
      ClothGridParams p;
      p.nx = p.ny = 10;
      p.stretch_stiffness = 1e2 * std::pow(100.0, double(s) / std::max(1, count - 1));
      scenes.push_back(makeClothGrid(p));
    }
    SimulatorOptions options = optionsFor(backend, Integrator::BackwardEuler);
    options.acceleration = acceleration;
    if (gradient_stop) {
      options.gradient_tolerance = 1e-2;
      options.iterations = 60;
    } else {
      options.tolerance = 1e-6;
      options.max_iterations = 60;
    }
    auto fixture = std::make_unique<BatchFixture>();
    fixture->batch = std::make_unique<BatchSimulator>(scenes, options);
    return fixture;
  });
  if (!f) return;
  PhaseTimes summed;
  double iterations = 0.0;
  for (auto _ : state) {
    const BatchStepReport& r = f->batch->step();
    summed += r.times;
    for (const StepReport& scene : r.scenes) iterations += scene.iterations;
  }
  setPhaseCounters(state, summed);
  state.counters["scenes"] = count;
  state.counters["iterations"] = iterations / (double(count) * double(state.iterations()));
}

}  // namespace

void registerBatchCases() {
  const std::vector<SceneCase> scenes = {{"chain", [] { return makeChainPendulum(); }}, {"cloth10", [] {
                                                                                           ClothGridParams p;
                                                                                           p.nx = 10;
                                                                                           p.ny = 10;
                                                                                           return makeClothGrid(p);
                                                                                         }}};
  for (BackendChoice backend : allBackends())
    for (const SceneCase& scene : scenes)
      for (int count : {100, 1000}) {
        // The goal's OpenCL cases: 1,000 chains, 100 and 1,000 cloths (the CPU has all four).
        if (backend != BackendChoice::Cpu && scene.name == "chain" && count == 100) continue;
        for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend})
          for (bool batched : {true, false}) {
            const std::string name = "batch/" + scene.name + "/" +
                                     (integrator == Integrator::BackwardEuler ? "BE" : "blend") + "/" +
                                     backendLabel(backend) + "/" + (batched ? "batch" : "separate");
            benchmark::RegisterBenchmark(
                name.c_str(),
                [=](benchmark::State& state) { runBatch(state, name, scene.make, backend, integrator, batched); })
                ->Arg(count)
                ->ArgName("scenes")
                ->Iterations(20)
                ->UseRealTime()
                ->Unit(benchmark::kMillisecond);
          }
      }
  for (BackendChoice backend : allBackends())
    for (BatchInput input : {BatchInput::Forces, BatchInput::State, BatchInput::States, BatchInput::Stiffness})
      for (int count : {100, 1000}) {
        const std::string name = std::string("batch_input/chain/BE/") + backendLabel(backend) + "/" + inputLabel(input);
        benchmark::RegisterBenchmark(
            name.c_str(), [=](benchmark::State& state) { runBatchInput(state, name, scenes[0].make, backend, input); })
            ->Arg(count)
            ->ArgName("scenes")
            ->Iterations(20)
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
      }
  for (BackendChoice backend : allBackends())
    for (const auto& [label, acceleration, gradient_stop] :
         {std::tuple{"plain", Acceleration::None, false}, std::tuple{"lbfgs", Acceleration::LBFGS, false},
          std::tuple{"lbfgs-gradient", Acceleration::LBFGS, true},
          std::tuple{"anderson", Acceleration::Anderson, false},
          std::tuple{"chebyshev", Acceleration::Chebyshev, false}, std::tuple{"newton", Acceleration::Newton, false}}) {
      const std::string name = std::string("batch_stops/cloth10/BE/") + backendLabel(backend) + "/" + label;
      benchmark::RegisterBenchmark(
          name.c_str(),
          [=](benchmark::State& state) { runBatchStops(state, name, backend, acceleration, gradient_stop); })
          ->Arg(100)
          ->ArgName("scenes")
          ->Iterations(20)
          ->UseRealTime()
          ->Unit(benchmark::kMillisecond);
    }
  // A Simulator as "a batch of one" (issue 22, docs/batch_design.md): the single-scene overhead of
  // the batch's driver, one scene stepped as a BatchSimulator of one ("batch") or as a Simulator
  // ("simulator"), 30 steps from rest. The ratio is what folding the two drivers into one costs a
  // single scene as the batch is now.
  std::vector<SceneCase> single = {scenes[0]};
  for (const SceneCase& reference : referenceScenes()) single.push_back(reference);
  for (BackendChoice backend : allBackends())
    for (const SceneCase& scene : single)
      for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend})
        for (bool batched : {true, false}) {
          const std::string name = "batch_of_one/" + scene.name + "/" +
                                   (integrator == Integrator::BackwardEuler ? "BE" : "blend") + "/" +
                                   backendLabel(backend) + "/" + (batched ? "batch" : "simulator");
          benchmark::RegisterBenchmark(
              name.c_str(),
              [=](benchmark::State& state) { runBatch(state, name, scene.make, backend, integrator, batched); })
              ->Arg(1)
              ->ArgName("scenes")
              ->Iterations(30)
              ->UseRealTime()
              ->Unit(benchmark::kMillisecond);
        }
}

}  // namespace stabint::bench
