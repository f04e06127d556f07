// Whole steps through the public API: Simulator::step() per integrator, backend and scene, and
// the cloth scaling family of BE and blend steps. The phase counters come from
// StepReport::times, averaged per step.
#include "bench_common.hpp"

#include <cmath>
#include <exception>

namespace stabint::bench {
namespace {

struct StepFixture {
  Scene scene;
  SimulatorOptions options;
  std::unique_ptr<Simulator> sim;
  void rebuild() { sim = std::make_unique<Simulator>(scene, options); }
};

// An explicit integrator on a stiff scene overflows within some tens of steps (omega h is in the
// hundreds); the cost of a step does not depend on the state, so the simulator is rebuilt
// (timing paused) once the energy leaves any physical range, before the step would be refused.
bool exploded(const StepReport& r) { return !(std::abs(r.energy.total()) < 1e30); }

// The first steps pay the CHOLMOD factorizations (one per distinct c) and, on OpenCL, the first
// kernel launches. The blend factors c = 1/h^2 only when it first takes the BE branch, so it
// warms up until it has.
void warmUp(StepFixture& f, int min_steps, int max_steps) {
  bool saw_be = f.options.integrator != Integrator::EnergyBlend;
  for (int i = 0; i < max_steps && (i < min_steps || !saw_be); ++i) {
    try {
      const StepReport& r = f.sim->step();
      saw_be = saw_be || r.branch == BlendBranch::BackwardEuler;
      if (exploded(r)) f.rebuild();
    } catch (const NonFiniteStateError&) {
      f.rebuild();
    }
  }
}

void runSteps(benchmark::State& state, const std::string& key, const std::function<Scene()>& make_scene,
              BackendChoice backend, Integrator integrator, int warm_min, int warm_max) {
  if (const std::string why = skipReason(backend); !why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  StepFixture* fixture = nullptr;
  try {
    fixture = &cachedFixture<StepFixture>(key, [&] {
      auto f = std::make_unique<StepFixture>();
      f->scene = make_scene();
      f->options = optionsFor(backend, integrator);
      f->rebuild();
      warmUp(*f, warm_min, warm_max);
      return f;
    });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  StepFixture& f = *fixture;

  PhaseTimes summed;
  double iterations = 0, energy_evaluations = 0, alpha = 0;
  double branch_im = 0, branch_be = 0, branch_fe = 0, rebuilds = 0;
  for (auto _ : state) {
    const StepReport* r = nullptr;
    try {
      r = &f.sim->step();
    } catch (const NonFiniteStateError&) {
      state.PauseTiming();
      f.rebuild();
      ++rebuilds;
      state.ResumeTiming();
      continue;
    }
    summed += r->times;
    iterations += r->iterations;
    energy_evaluations += r->energy_evaluations;
    alpha += r->alpha;
    branch_im += r->branch == BlendBranch::ImplicitMidpoint;
    branch_be += r->branch == BlendBranch::BackwardEuler;
    branch_fe += r->branch == BlendBranch::ForwardEuler;
    if (exploded(*r)) {
      state.PauseTiming();
      f.rebuild();
      ++rebuilds;
      state.ResumeTiming();
    }
  }

  using benchmark::Counter;
  setSizeCounters(state, f.scene);
  setPhaseCounters(state, summed);
  state.counters["iterations"] = Counter(iterations, Counter::kAvgIterations);
  state.counters["energy_evaluations"] = Counter(energy_evaluations, Counter::kAvgIterations);
  // Time of one local/global iteration inside the step: the phases the iterations run in.
  if (iterations > 0)
    state.counters["iteration_time"] =
        (summed.local + summed.gather + summed.transfer + summed.global) / iterations;
  if (integrator == Integrator::EnergyBlend) {
    state.counters["branch_IM"] = Counter(branch_im, Counter::kAvgIterations);
    state.counters["branch_BE"] = Counter(branch_be, Counter::kAvgIterations);
    state.counters["branch_FE"] = Counter(branch_fe, Counter::kAvgIterations);
    state.counters["alpha"] = Counter(alpha, Counter::kAvgIterations);
  }
  if (rebuilds > 0) state.counters["rebuilds"] = rebuilds;
  state.SetLabel(f.sim->backendDescription());
}

}  // namespace

void registerStepCases() {
  for (const SceneCase& scene : referenceScenes())
    for (Integrator integrator : allIntegrators())
      for (BackendChoice backend : allBackends()) {
        const std::string name =
            "step/" + scene.name + "/" + integratorName(integrator) + "/" + backendLabel(backend);
        benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& state) {
          runSteps(state, name, scene.make, backend, integrator, 3, 20);
        })->UseRealTime()->Unit(benchmark::kMicrosecond);
      }

  // Scaling: BE and blend steps on growing cloths, cpu and OpenCL double.
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend})
    for (BackendChoice backend : {BackendChoice::Cpu, BackendChoice::OpenCLDouble}) {
      const std::string name = std::string("scaling_step/cloth/") + integratorName(integrator) + "/" +
                               backendLabel(backend);
      auto* b = benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& state) {
        const int side = static_cast<int>(state.range(0));
        runSteps(state, name + "/" + std::to_string(side), [side] { return clothScene(side); }, backend,
                 integrator, 2, 8);
      });
      for (int side : scalingSides()) b->Arg(side);
      b->ArgName("side")->UseRealTime()->Unit(benchmark::kMicrosecond);
    }
}

}  // namespace stabint::bench
