// Whole steps through the public API: Simulator::step() per integrator, backend and scene, and
// the cloth scaling family of BE and blend steps. The phase counters come from
// StepReport::times, averaged per step.
#include "bench_common.hpp"

#include <chrono>
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
// Returns the number of steps taken.
int warmUp(StepFixture& f, int min_steps, int max_steps) {
  bool saw_be = f.options.integrator != Integrator::EnergyBlend;
  int i = 0;
  for (; i < max_steps && (i < min_steps || !saw_be); ++i) {
    try {
      const StepReport& r = f.sim->step();
      saw_be = saw_be || r.branch == BlendBranch::BackwardEuler;
      if (exploded(r)) f.rebuild();
    } catch (const NonFiniteStateError&) {
      f.rebuild();
    }
  }
  return i;
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
  double branch_im = 0, branch_be = 0, branch_scale = 0, rebuilds = 0;
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
    branch_scale += r->branch == BlendBranch::VelocityScale;
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
    state.counters["iteration_time"] = (summed.local + summed.gather + summed.transfer + summed.global) / iterations;
  if (integrator == Integrator::EnergyBlend) {
    state.counters["branch_IM"] = Counter(branch_im, Counter::kAvgIterations);
    state.counters["branch_BE"] = Counter(branch_be, Counter::kAvgIterations);
    state.counters["branch_scale"] = Counter(branch_scale, Counter::kAvgIterations);
    state.counters["alpha"] = Counter(alpha, Counter::kAvgIterations);
  }
  if (rebuilds > 0) state.counters["rebuilds"] = rebuilds;
  state.SetLabel(f.sim->backendDescription());
}

// The blend against BE with the same options (main iteration count 10), stepped alternately in
// one case so that other load on a shared machine hits both alike: each benchmark iteration is
// one BE step and one blend step, each timed on its own. The two simulators start from the same
// state and advance in lock step.
// With `restart_steps` > 0 both go back to their first state (Simulator::restore, timing paused)
// every that many steps, so that a long run keeps measuring the same stretch of motion (the
// violent scenes' fall and swing) instead of whatever the simulation has come to.
struct PairFixture {
  StepFixture be, blend;
  Checkpoint be_start, blend_start;
  int since_restart = 0;
};

void runPair(benchmark::State& state, const std::string& key, const std::function<Scene()>& make_scene,
             BackendChoice backend, int restart_steps = 0) {
  if (const std::string why = skipReason(backend); !why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  PairFixture* fixture = nullptr;
  try {
    fixture = &cachedFixture<PairFixture>(key, [&] {
      auto f = std::make_unique<PairFixture>();
      for (StepFixture* s : {&f->be, &f->blend}) {
        s->scene = make_scene();
        s->options = optionsFor(backend, s == &f->be ? Integrator::BackwardEuler : Integrator::EnergyBlend);
        s->rebuild();
      }
      const int steps = warmUp(f->blend, 3, 20);
      warmUp(f->be, steps, steps);  // same step index: both integrate the same time span
      f->be_start = f->be.sim->checkpoint();
      f->blend_start = f->blend.sim->checkpoint();
      return f;
    });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  PairFixture& f = *fixture;
  using Clock = std::chrono::steady_clock;
  double be_time = 0, blend_time = 0, be_iterations = 0, blend_iterations = 0;
  double branch_im = 0, branch_be = 0, branch_scale = 0, blend_energy_evaluations = 0;
  PhaseTimes be_phases, blend_phases;
  try {
    for (auto _ : state) {
      if (restart_steps > 0 && ++f.since_restart > restart_steps) {
        state.PauseTiming();
        f.be.sim->restore(f.be_start);
        f.blend.sim->restore(f.blend_start);
        f.since_restart = 1;
        state.ResumeTiming();
      }
      auto start = Clock::now();
      const StepReport& be = f.be.sim->step();
      be_time += std::chrono::duration<double>(Clock::now() - start).count();
      be_iterations += be.iterations;
      be_phases += be.times;
      start = Clock::now();
      const StepReport& r = f.blend.sim->step();
      blend_time += std::chrono::duration<double>(Clock::now() - start).count();
      blend_phases += r.times;
      blend_iterations += r.iterations;
      blend_energy_evaluations += r.energy_evaluations;
      branch_im += r.branch == BlendBranch::ImplicitMidpoint;
      branch_be += r.branch == BlendBranch::BackwardEuler;
      branch_scale += r.branch == BlendBranch::VelocityScale;
    }
  } catch (const NonFiniteStateError& e) {
    state.SkipWithError(e.what());
    return;
  }
  using benchmark::Counter;
  setSizeCounters(state, f.be.scene);
  state.counters["be_step"] = Counter(be_time, Counter::kAvgIterations);
  state.counters["blend_step"] = Counter(blend_time, Counter::kAvgIterations);
  state.counters["overhead"] = be_time > 0 ? blend_time / be_time - 1.0 : 0.0;
  state.counters["be_iterations"] = Counter(be_iterations, Counter::kAvgIterations);
  state.counters["blend_iterations"] = Counter(blend_iterations, Counter::kAvgIterations);
  state.counters["blend_energy_evaluations"] = Counter(blend_energy_evaluations, Counter::kAvgIterations);
  state.counters["branch_IM"] = Counter(branch_im, Counter::kAvgIterations);
  state.counters["branch_BE"] = Counter(branch_be, Counter::kAvgIterations);
  state.counters["branch_scale"] = Counter(branch_scale, Counter::kAvgIterations);
  // Where the time goes, per step: the host solves, the element passes of the iterations (local,
  // with the gather and transfers on OpenCL) and the energy passes and reductions.
  for (const auto& [prefix, t] :
       {std::pair<const char*, const PhaseTimes&>{"be_", be_phases}, {"blend_", blend_phases}}) {
    state.counters[std::string(prefix) + "global"] = Counter(t.global, Counter::kAvgIterations);
    state.counters[std::string(prefix) + "local"] = Counter(t.local + t.gather + t.transfer, Counter::kAvgIterations);
    state.counters[std::string(prefix) + "energy"] = Counter(t.energy, Counter::kAvgIterations);
    state.counters[std::string(prefix) + "other"] = Counter(t.bookkeeping, Counter::kAvgIterations);
  }
  state.SetLabel(f.be.sim->backendDescription());
}

}  // namespace

void registerStepCases() {
  // A fixed number of steps per repetition, restarted from the same state, so that every
  // repetition (and every build compared) times the same stretch of motion with the same mix of
  // blend branches: the first 2 s of the reference scenes (60 steps), and 4 times the first 5 s
  // (150 steps: the fall and the first swings) of the main job's violent scenes.
  for (const SceneCase& scene : referenceScenes())
    for (BackendChoice backend : allBackends()) {
      const std::string name = "blend_vs_be/" + scene.name + "/" + backendLabel(backend);
      benchmark::RegisterBenchmark(name.c_str(),
                                   [=](benchmark::State& state) { runPair(state, name, scene.make, backend, 60); })
          ->Iterations(60)
          ->UseRealTime()
          ->Unit(benchmark::kMillisecond);
    }
  for (const SceneCase& scene : violentScenes())
    for (BackendChoice backend : allBackends()) {
      const std::string name = "blend_vs_be/" + scene.name + "/" + backendLabel(backend);
      benchmark::RegisterBenchmark(name.c_str(),
                                   [=](benchmark::State& state) { runPair(state, name, scene.make, backend, 150); })
          ->Iterations(600)
          ->UseRealTime()
          ->Unit(benchmark::kMicrosecond);
    }

  for (const SceneCase& scene : referenceScenes())
    for (Integrator integrator : allIntegrators())
      for (BackendChoice backend : allBackends()) {
        const std::string name = "step/" + scene.name + "/" + integratorName(integrator) + "/" + backendLabel(backend);
        benchmark::RegisterBenchmark(
            name.c_str(),
            [=](benchmark::State& state) { runSteps(state, name, scene.make, backend, integrator, 3, 20); })
            ->UseRealTime()
            ->Unit(benchmark::kMicrosecond);
      }

  // Scaling: BE and blend steps on growing cloths, cpu and OpenCL double.
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend})
    for (BackendChoice backend : {BackendChoice::Cpu, BackendChoice::OpenCLDouble}) {
      const std::string name =
          std::string("scaling_step/cloth/") + integratorName(integrator) + "/" + backendLabel(backend);
      auto* b = benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& state) {
        const int side = static_cast<int>(state.range(0));
        runSteps(
            state, name + "/" + std::to_string(side), [side] { return clothScene(side); }, backend, integrator, 2, 8);
      });
      for (int side : scalingSides()) b->Arg(side);
      b->ArgName("side")->UseRealTime()->Unit(benchmark::kMicrosecond);
    }

  // BackendKind::Auto's rule: a BE and a blend step (10 iterations each, stepped alternately as in
  // blend_vs_be) per backend on the scenes of autoRuleScenes().
  for (const SceneCase& scene : autoRuleScenes())
    for (BackendChoice backend : allBackends()) {
      const std::string name = "auto_step/" + scene.name + "/" + backendLabel(backend);
      benchmark::RegisterBenchmark(name.c_str(),
                                   [=](benchmark::State& state) { runPair(state, name, scene.make, backend); })
          ->UseRealTime()
          ->Unit(benchmark::kMillisecond);
    }
}

}  // namespace stabint::bench
