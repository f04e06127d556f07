// The tet bar's frame on the CPU's threads (issue 11's headline: a blend frame of the 50 x 10 x 10
// tet bar at 10 iterations in at most 33 ms). Each case runs with a thread count set for the
// process (setCpuThreads, restored afterwards); the thread count changes no result, so the
// variants of one scene time the same motion:
//   frame/<scene>/<integrator>/<backend>/threads:N   Simulator::step(), 30 steps per repetition
//                                                    from the same checkpoint
//   frame/cloth128x128/BE-chebyshev-<factor|cg10>/<backend>
//                                                    the GPU-sized frame: a 128 x 128 spring cloth
//                                                    (16,384 particles), BE with the Chebyshev
//                                                    semi-iteration (Wang 2015's GPU projective
//                                                    dynamics), 10 iterations, the global step by
//                                                    the host factor or 10 device CG iterations;
//                                                    30 steps (5 with STABINT_BENCH_QUICK), the
//                                                    process's default threads
//   frame_pass/<scene>/<local|energy>/threads:N      one element pass of the CPU reference: the
//                                                    local step with its right-hand side, or an
//                                                    energy pass, at the bar's positions after 10
//                                                    blend steps (deformed, as in a frame); with
//                                                    its arithmetic bound (counters flops, the
//                                                    core's rates, arithmetic_bound, bound_ratio:
//                                                    below)
//   frame_solve/<scene>/<one_solve|library>/threads:N
//                                                    the host's solve of K_c x = rhs alone (manual
//                                                    time, after a local step): Eigen's one
//                                                    CHOLMOD solve of the three columns, or
//                                                    GlobalSystem::solve (one pass over the factor
//                                                    on the calling thread; it was two column
//                                                    groups on two threads, "column_groups")
#include "bench_common.hpp"
#include "first_step.hpp"

#include "common/worker_pool.hpp"
#include "elements/element_type.hpp"
#include "elements/projections.hpp"

#include <Eigen/CholmodSupport>

#include <chrono>
#include <cmath>
#include <exception>

namespace stabint::bench {
namespace {

using namespace first_step;
constexpr int kFrameSteps = 30;

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

void runFrame(benchmark::State& state, const std::string& key, const std::function<Scene()>& make,
              const SimulatorOptions& options, BackendChoice backend, int threads) {
  if (const std::string why = skipReason(backend); !why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  ThreadsFor setting(threads);
  FrameFixture* fixture = nullptr;
  try {
    fixture = &cachedFixture<FrameFixture>(key, [&] {
      auto f = std::make_unique<FrameFixture>();
      f->scene = make();
      f->sim = std::make_unique<Simulator>(f->scene, options);
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

// ---- the local step's arithmetic bound ---------------------------------------------------------
// Operations of one tet in a local step, counted from the code lane by lane (every lane of a
// group executes them): multiplies and adds, and apart from them the divisions and square roots,
// which take many cycles each.
//   A x (kindLanes): 4 vertices x 9 products + 27 sums                               63
//   rotation set-up (nearestRotations): ||m||^2 18, cofactors 32, flatness test 3     53 + 1 sqrt
//   per Newton iteration: step weights 2, update and its size 54, cofactors 32        88 + 1 div
//   per scaled iteration, besides: ||X||^2 and ||C||^2 36                             36 + 2 div, 2 sqrt
//   energy 29; contributions: w p 9, A^T p 4 x 3 x 5 = 60                             98
struct TetWork {
  double muladds = 0.0, divisions = 0.0, roots = 0.0;
};

// One core's rates of 8-wide multiplies and adds (independent chains, so both pipes stay busy;
// no fused multiply-add, as in the library's build), divisions and square roots: what the element
// passes' instructions can reach. Cloned like the passes, so it runs at the width they run at.
struct VectorRates {
  double muladds = 0.0, divisions = 0.0, roots = 0.0;  // per second, per core
};
STABINT_TARGET_CLONES VectorRates vectorRates(int rounds) {
  constexpr int W = projections::kLanes;
  using Clock = std::chrono::steady_clock;
  double a[8][W], b[8][W];
  for (int j = 0; j < 8; ++j)
    for (int l = 0; l < W; ++l) a[j][l] = 1.0 + 1e-3 * (j + l), b[j][l] = 1e-3 * (j - l);
  VectorRates rates;
  auto start = Clock::now();
  for (int r = 0; r < rounds; ++r)
    for (int j = 0; j < 8; ++j)
      for (int l = 0; l < W; ++l) {
        a[j][l] *= 0.9999999;
        b[j][l] += 1e-9;
      }
  rates.muladds = 2.0 * 8 * W * rounds / std::chrono::duration<double>(Clock::now() - start).count();
  start = Clock::now();
  for (int r = 0; r < rounds / 8; ++r)
    for (int j = 0; j < 8; ++j)
      for (int l = 0; l < W; ++l) a[j][l] = 1.0000001 / a[j][l];
  rates.divisions = 8.0 * W * (rounds / 8) / std::chrono::duration<double>(Clock::now() - start).count();
  start = Clock::now();
  for (int r = 0; r < rounds / 8; ++r)
    for (int j = 0; j < 8; ++j)
      for (int l = 0; l < W; ++l) b[j][l] = std::sqrt(b[j][l] + 1.0);
  rates.roots = 8.0 * W * (rounds / 8) / std::chrono::duration<double>(Clock::now() - start).count();
  double keep = 0.0;
  for (int j = 0; j < 8; ++j)
    for (int l = 0; l < W; ++l) keep += a[j][l] + b[j][l];
  benchmark::DoNotOptimize(keep);
  return rates;
}

// The operations of one tet local step at positions x: each group of 8 tets rotated as the pass
// does, its Newton iterations counted.
TetWork tetPassWork(const SceneData& data, const Eigen::MatrixX3d& x) {
  constexpr int W = projections::kLanes;
  TetWork work;
  for (const ElementBlock& block : data.blocks()) {
    if (std::string(block.type->identifier()) != "tet") continue;
    for (int first = 0; first < block.count; first += W) {
      double m[9][W], r[9][W];
      for (int l = 0; l < W; ++l) {
        const int e = std::min(first + l, block.count - 1);
        for (int row = 0; row < 3; ++row)
          for (int col = 0; col < 3; ++col) {
            double v = 0.0;
            for (int k = 0; k < 4; ++k)
              v += block.coefficients[std::size_t(12 * e + 4 * row + k)] *
                   x(block.vertices[std::size_t(4 * e + k)], col);
            m[3 * row + col][l] = v;
          }
      }
      projections::RotationWork group;
      projections::nearestRotations(m, r, &group);
      work.muladds += W * (63 + 53 + 98 + 88.0 * group.iterations + 36.0 * group.scaled_iterations);
      work.divisions += W * (group.iterations + 2.0 * group.scaled_iterations);
      work.roots += W * (1 + 2.0 * group.scaled_iterations);
    }
  }
  return work;
}

// The first-step fixture, moved to the bar's positions after 10 blend steps (bent under gravity,
// as in the frame cases), with CHOLMOD's own solve of the three columns beside the library's.
struct PassFixture : Fixture {
  explicit PassFixture(const Scene& s) : Fixture(s, BackendChoice::Cpu) {
    Simulator sim(s, optionsFor(BackendChoice::Cpu, Integrator::EnergyBlend));
    for (int i = 0; i < 10; ++i) sim.step();
    const Eigen::MatrixX3d bent = sim.positions();
    backend->write(kX, bent);
    tet_work = tetPassWork(data, bent);
    // CHOLMOD's solve through Eigen: one cholmod_solve of the three columns.
    Eigen::SparseMatrix<double> k = system.stiffnessLaplacian();
    for (Eigen::Index j = 0; j < k.rows(); ++j) k.coeffRef(j, j) += kC * system.masses()[j];
    one_solve.compute(k);
  }
  Eigen::CholmodSimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> one_solve;
  TetWork tet_work;
};

PassFixture* passFixture(benchmark::State& state) {
  try {
    return &cachedFixture<PassFixture>("frame_pass", [] { return std::make_unique<PassFixture>(tetBar().make()); });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return nullptr;
  }
}

// The arithmetic bound of a pass on `threads` cores: its operations at the measured rates (an
// energy pass skips the contributions' 69 operations per tet, a small share left in the count).
void runPass(benchmark::State& state, bool energy_only, int threads) {
  ThreadsFor setting(threads);
  PassFixture* f = passFixture(state);
  if (!f) return;
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    if (energy_only) {
      benchmark::DoNotOptimize(f->backend->potential(kX, kTimeStep));
    } else {
      f->backend->localStepRhs(kX, kY, kC, kTimeStep, f->rhs);
      benchmark::DoNotOptimize(f->rhs.data());
    }
  }
  const double per_pass =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / double(state.iterations());
  // The fastest of a few short trials: the rates are the machine's, not the neighbours' load.
  VectorRates rates;
  for (int trial = 0; trial < 7; ++trial) {
    const VectorRates r = vectorRates(300'000);
    rates.muladds = std::max(rates.muladds, r.muladds);
    rates.divisions = std::max(rates.divisions, r.divisions);
    rates.roots = std::max(rates.roots, r.roots);
  }
  const TetWork& w = f->tet_work;
  const double bound = (w.muladds / rates.muladds + w.divisions / rates.divisions + w.roots / rates.roots) / threads;
  state.counters["threads"] = threads;
  state.counters["flops"] = w.muladds + w.divisions + w.roots;
  state.counters["muladds_per_s"] = rates.muladds;
  state.counters["divisions_per_s"] = rates.divisions;
  state.counters["roots_per_s"] = rates.roots;
  state.counters["arithmetic_bound"] = bound;
  state.counters["bound_ratio"] = per_pass / bound;
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
        benchmark::RegisterBenchmark(name.c_str(),
                                     [=](benchmark::State& state) {
                                       runFrame(
                                           state, base, [] { return tetBar().make(); }, optionsFor(backend, integrator),
                                           backend, threads);
                                     })
            ->Iterations(kFrameSteps)
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
      }
  for (int cg : {0, 10})
    for (BackendChoice backend : allBackends()) {
      const std::string name = std::string("frame/cloth128x128/BE-chebyshev-") +
                               (cg == 0 ? std::string("factor") : "cg" + std::to_string(cg)) + "/" +
                               backendLabel(backend);
      SimulatorOptions options = optionsFor(backend, Integrator::BackwardEuler);
      options.acceleration = Acceleration::Chebyshev;
      if (cg > 0) {
        options.global_solve = GlobalSolve::ConjugateGradient;
        options.cg_iterations = cg;
      }
      benchmark::RegisterBenchmark(name.c_str(),
                                   [=](benchmark::State& state) {
                                     runFrame(
                                         state, name, [] { return clothScene(128); }, options, backend, cpuThreads());
                                   })
          ->Iterations(quickMode() ? 5 : kFrameSteps)
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
