// Accuracy per iteration budget (issue 19, docs/benchmarks.md "Convergence"): BE from rest for
// a fixed number of frames with each solver at a fixed budget, against the same BE with every
// solve converged (L-BFGS to a 1e-13 relative objective change, at most 20,000 iterations, on the
// CPU reference; cached per scene for the run).
//   convergence/<scene>/<solver>/<iterations>/<backend>
//     scene   peercloth50: the peers' cloth (ShapeOp's and GenPD's comparison scene), 50 x 50
//             particles, 1 m square, horizontal, the two corners of one edge pinned (k = 1e6),
//             0.1 kg in all, structural, shear and skip-one bending springs of 1e4, 1e4, 1e3 N/m;
//             30 frames; the builder lumps the mass by area (an edge particle has half an inner
//             one's, a corner a quarter);
//             peercloth50uniform: the same cloth with GenPD's masses, every particle the same
//             (its cloth builder's unit_mass = total mass / particles), as in issue 19's figures
//             for GenPD; 30 frames;
//             tetbar50x10x10: the reference tet bar (5,000 particles); 10 frames
//     solver  plain, anderson, lbfgs (SimulatorOptions::acceleration); lbfgs-gradient<tol>: L-BFGS
//             with SimulatorOptions::gradient_tolerance = tol, the budget its cap (100)
// Counters: rms_error [m] (RMS over particles of the distance to the converged run after the
// last frame), iterations_per_frame (as the steps report them), us_per_iteration (the case's
// time per frame over its iterations per frame).
//   solve_phases/<scene>/<solver>/<backend>  one BE solve of 20 iterations from the same state
//             (the scene's rest positions one step of free fall on), the LocalGlobalSolver driven
//             directly; per iteration: us_per_iteration, the backend's phase times (local,
//             global, energy, transfer, ...) and host = the rest (L-BFGS's vector work on the
//             host, the line search's bookkeeping). What an L-BFGS iteration costs more than a
//             plain one, phase by phase (docs/benchmarks.md, "L-BFGS's cost per iteration").
#include "bench_common.hpp"

#include "backend/backend.hpp"
#include "cpu/cpu_backend.hpp"
#include "opencl/opencl_backend.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"
#include "solver/local_global.hpp"

#include <chrono>
#include <cmath>
#include <exception>
#include <map>

namespace stabint::bench {
namespace {

Scene peerCloth() {
  ClothGridParams p;
  p.nx = p.ny = 50;
  p.areal_density = 0.1;  // 0.1 kg over 1 m^2
  p.stretch_stiffness = 1e4;
  p.shear_stiffness = 1e4;
  p.bend_stiffness = 1e3;
  p.pin_stiffness = 1e6;
  Scene s = makeClothGrid(p);
  // Horizontal: the grid's y becomes -z, so the cloth lies in the x-z plane and falls along -y.
  for (int r = 0; r < s.numParticles(); ++r) {
    s.positions(r, 2) = -s.positions(r, 1);
    s.positions(r, 1) = 0.0;
  }
  for (Pin& pin : s.pins) pin.target.position = s.positions.row(pin.vertex).transpose();
  return s;
}

Scene peerClothUniformMass() {
  Scene s = peerCloth();
  s.masses.setConstant(s.masses.sum() / s.numParticles());
  return s;
}

struct ConvergenceScene {
  std::string name;
  std::function<Scene()> make;
  int frames;
  std::vector<int> budgets;
};

const std::vector<ConvergenceScene>& convergenceScenes() {
  static const std::vector<ConvergenceScene> scenes{
      {"peercloth50", peerCloth, 30, {10, 20, 40}},
      {"peercloth50uniform", peerClothUniformMass, 30, {10, 20, 40}},
      {"tetbar50x10x10", referenceScenes()[1].make, 10, {10, 20}},
  };
  return scenes;
}

Eigen::MatrixX3d runFrames(const Scene& scene, const SimulatorOptions& options, int frames) {
  Simulator sim(scene, options);
  for (int f = 0; f < frames; ++f) sim.step();
  return sim.positions();
}

const Eigen::MatrixX3d& convergedPositions(const ConvergenceScene& c) {
  static std::map<std::string, Eigen::MatrixX3d> cache;
  auto it = cache.find(c.name);
  if (it != cache.end()) return it->second;
  SimulatorOptions o;
  o.integrator = Integrator::BackwardEuler;
  o.acceleration = Acceleration::LBFGS;
  o.tolerance = 1e-13;
  o.max_iterations = 20000;
  return cache.emplace(c.name, runFrames(c.make(), o, c.frames)).first->second;
}

double rmsDistance(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  return std::sqrt((a - b).rowwise().squaredNorm().mean());
}

void runConvergence(benchmark::State& state, const ConvergenceScene& c, Acceleration solver, int iterations,
                    double gradient_tolerance, BackendChoice backend) {
  if (const std::string why = skipReason(backend); !why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  try {
    const Scene scene = c.make();
    const Eigen::MatrixX3d& converged = convergedPositions(c);
    SimulatorOptions o = optionsFor(backend, Integrator::BackwardEuler);
    o.acceleration = solver;
    o.iterations = iterations;
    o.gradient_tolerance = gradient_tolerance;
    double error = 0.0;
    long done = 0;
    for (auto _ : state) {
      state.PauseTiming();
      Simulator sim(scene, o);  // the factorization is not the solve's cost
      state.ResumeTiming();
      done = 0;
      for (int f = 0; f < c.frames; ++f) done += sim.step().iterations;
      state.PauseTiming();
      error = rmsDistance(sim.positions(), converged);
      state.ResumeTiming();
    }
    state.counters["rms_error"] = error;
    state.counters["iterations_per_frame"] = double(done) / c.frames;
    state.counters["us_per_iteration"] = benchmark::Counter(
        1e-6 * double(done), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
    setSizeCounters(state, scene);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
}

struct PhaseFixture {
  enum { kX, kY, kScratch, kSlots };
  static constexpr double kH = 1.0 / 30.0;
  PhaseFixture(const Scene& s, BackendChoice choice)
      : scene(s),
        data(s),
        backend(choice == BackendChoice::Cpu
                    ? makeCpuBackend(data, forcing, kSlots)
                    : makeOpenCLBackend(data, forcing, kSlots, optionsFor(choice, Integrator::BackwardEuler).opencl)),
        system(data),
        solver(*backend, system, kScratch) {
    y = s.positions;
    for (Eigen::Index j = 0; j < y.rows(); ++j) y.row(j) += (kH * kH * s.gravity).transpose();
    solver.setScene(data, forcing);  // the rigid motions' coarse space needs the one-particle elements
  }
  Scene scene;
  SceneData data;
  Forcing forcing{data.scene()};
  std::unique_ptr<Backend> backend;
  GlobalSystem system;
  LocalGlobalSolver solver;
  Eigen::MatrixX3d y;
};

void runSolvePhases(benchmark::State& state, const ConvergenceScene& c, Acceleration solver, BackendChoice choice) {
  if (const std::string why = skipReason(choice); !why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  PhaseFixture* fixture = nullptr;
  try {
    fixture = &cachedFixture<PhaseFixture>("solve_phases/" + c.name + "/" + backendLabel(choice),
                                           [&] { return std::make_unique<PhaseFixture>(c.make(), choice); });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  PhaseFixture& f = *fixture;
  IterationControl control;
  control.iterations = control.max_iterations = 20;
  control.acceleration = solver;
  // As a Simulator's BE solve with the default options: L-BFGS takes the rigid motions
  // (SimulatorOptions::lbfgs_rigid_modes); plain iterations ignore the flag.
  control.rigid_modes = SimulatorOptions{}.lbfgs_rigid_modes != 0;
  const double cc = 1.0 / (PhaseFixture::kH * PhaseFixture::kH);
  auto once = [&] {
    f.backend->write(PhaseFixture::kY, f.y);
    f.backend->write(PhaseFixture::kX, f.y);
    return f.solver.solve(cc, PhaseFixture::kY, PhaseFixture::kX, 0.0, control);
  };
  once();  // the factorization, the first launches
  f.backend->times() = PhaseTimes{};
  double iterations = 0.0, seconds = 0.0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    iterations += once();
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  const PhaseTimes& t = f.backend->times();
  auto perIteration = [&](double s) { return 1e6 * s / std::max(iterations, 1.0); };
  state.counters["us_per_iteration"] = perIteration(seconds);
  state.counters["local"] = perIteration(t.local);
  state.counters["global"] = perIteration(t.global);
  state.counters["energy"] = perIteration(t.energy);
  state.counters["transfer"] = perIteration(t.transfer + t.gather);
  state.counters["host"] = perIteration(seconds - t.total());
  setSizeCounters(state, f.scene);
}

}  // namespace

void registerConvergenceCases() {
  for (const ConvergenceScene& c : convergenceScenes())
    for (const auto& [label, solver] :
         {std::pair{"plain", Acceleration::None}, std::pair{"lbfgs", Acceleration::LBFGS}})
      for (BackendChoice backend : allBackends()) {
        const std::string name = "solve_phases/" + c.name + "/" + label + "/" + backendLabel(backend);
        const Acceleration s = solver;
        benchmark::RegisterBenchmark(name.c_str(), [c, s, backend](benchmark::State& state) {
          runSolvePhases(state, c, s, backend);
        })->UseRealTime();
      }
  for (const ConvergenceScene& c : convergenceScenes())
    for (const auto& [label, solver] :
         {std::pair{"plain", Acceleration::None}, std::pair{"anderson", Acceleration::Anderson},
          std::pair{"lbfgs", Acceleration::LBFGS}, std::pair{"newton", Acceleration::Newton}})
      for (int iterations : c.budgets)
        for (BackendChoice backend : allBackends()) {
          const std::string name =
              "convergence/" + c.name + "/" + label + "/" + std::to_string(iterations) + "/" + backendLabel(backend);
          const Acceleration s = solver;
          benchmark::RegisterBenchmark(name.c_str(),
                                       [c, s, iterations, backend](benchmark::State& state) {
                                         runConvergence(state, c, s, iterations, 0.0, backend);
                                       })
              ->UseRealTime()
              ->Unit(benchmark::kMillisecond);
        }
  // The stopping rule by accuracy: the iterations a gradient tolerance takes and the error it
  // leaves, with a cap of 100.
  for (const ConvergenceScene& c : convergenceScenes())
    for (const double tolerance : {1e-1, 1e-2, 1e-3})
      for (BackendChoice backend : allBackends()) {
        char label[32];
        std::snprintf(label, sizeof label, "lbfgs-gradient%g", tolerance);
        const std::string name = "convergence/" + c.name + "/" + label + "/100/" + backendLabel(backend);
        benchmark::RegisterBenchmark(name.c_str(),
                                     [c, tolerance, backend](benchmark::State& state) {
                                       runConvergence(state, c, Acceleration::LBFGS, 100, tolerance, backend);
                                     })
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
      }
}

}  // namespace stabint::bench
