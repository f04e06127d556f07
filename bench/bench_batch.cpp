// batch/<scene>/BE/cpu/<variant>/scenes:N: N small scenes advanced one step each, either as one
// BatchSimulator (variant "batch": one solve and one factor for all) or as N Simulators one after
// another ("separate"). The ratio of the two is the batch's gain (docs/batch_design.md, the
// benchmark that judges issue 11 item 3; OpenCL cases follow once the batch runs there).
#include "bench_common.hpp"

#include "integrator/batch_simulator.hpp"

namespace stabint::bench {
namespace {

struct BatchFixture {
  std::unique_ptr<BatchSimulator> batch;
  std::vector<Simulator> separate;
};

void runBatch(benchmark::State& state, const std::string& name, const std::function<Scene()>& make, bool batched) {
  const int count = static_cast<int>(state.range(0));
  // A fresh fixture per case function call: every repetition times the same steps from rest.
  releaseAllFixtures();
  BatchFixture& f = cachedFixture<BatchFixture>(name, [&] {
    auto fixture = std::make_unique<BatchFixture>();
    const std::vector<Scene> scenes(static_cast<std::size_t>(count), make());
    const SimulatorOptions options = optionsFor(BackendChoice::Cpu, Integrator::BackwardEuler);
    if (batched) {
      fixture->batch = std::make_unique<BatchSimulator>(scenes, options);
    } else {
      for (const Scene& s : scenes) fixture->separate.emplace_back(s, options);
    }
    return fixture;
  });
  for (auto _ : state) {
    if (batched) {
      benchmark::DoNotOptimize(f.batch->step());
    } else {
      for (Simulator& s : f.separate) benchmark::DoNotOptimize(s.step());
    }
  }
  state.counters["scenes"] = count;
  state.SetLabel(batched ? "one BatchSimulator" : "one Simulator per scene");
}

}  // namespace

void registerBatchCases() {
  const std::vector<SceneCase> scenes = {{"chain", [] { return makeChainPendulum(); }}, {"cloth10", [] {
                                                                                           ClothGridParams p;
                                                                                           p.nx = 10;
                                                                                           p.ny = 10;
                                                                                           return makeClothGrid(p);
                                                                                         }}};
  for (const SceneCase& scene : scenes)
    for (int count : {100, 1000})
      for (bool batched : {true, false}) {
        const std::string name = "batch/" + scene.name + "/BE/cpu/" + (batched ? "batch" : "separate");
        benchmark::RegisterBenchmark(name.c_str(),
                                     [=](benchmark::State& state) { runBatch(state, name, scene.make, batched); })
            ->Arg(count)
            ->ArgName("scenes")
            ->Iterations(20)
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
      }
}

}  // namespace stabint::bench
