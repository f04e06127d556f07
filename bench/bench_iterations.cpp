// Exactly one local/global iteration: the internal LocalGlobalSolver driven directly with a
// backend and the prefactored GlobalSystem (as tests/test_local_global.cpp does). One iteration
// is local projections + gather of the right-hand side + its transfer to the host + the CHOLMOD
// solve + the transfer of the new positions back.
//   auto_iteration/<scene>/BE/<backend>  one BE iteration on the scenes of autoRuleScenes(), the
//                               figures behind BackendKind::Auto's rule.
//   global_step/<scene>/<solver>/<backend>  one local/global iteration with the CHOLMOD factor
//                               (factor) or GlobalSolve::ConjugateGradient with k CG iterations
//                               (cg<k>; on OpenCL on the device, nothing read back); the counter
//                               position_error is, after one frame's BE solve of 10 iterations
//                               from the same start, the largest distance from the CPU factor's
//                               result, relative to the body's size (speed against accuracy).
//   global_step_scaling/<tetbar>/<solver>/<backend>  the same, factor and cg10, on the tet bars
//                               of autoRuleScenes().
//   rotation/<scene>/<method>   the nearest rotation of every tet's F at the same state, alone,
//                               per tet (items_per_second): the library's (newton-polar), Eigen's
//                               Jacobi SVD (jacobi-svd, the method it replaced) and one
//                               warm-started quaternion step (warm-quaternion-1, Mueller et al.
//                               2016, from each tet's rotation at the rest shape; the
//                               alternative docs/elements.md weighs); the counter max_error is
//                               each method's largest distance from the Jacobi SVD's rotation.
#include "bench_common.hpp"

#include "backend/backend.hpp"
#include "cpu/cpu_backend.hpp"
#include "elements/projections.hpp"
#include "integrator/integrator_steps.hpp"
#include "opencl/opencl_backend.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"
#include "solver/local_global.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <exception>
#include <initializer_list>
#include <utility>
#include <vector>

namespace stabint::bench {
namespace {

enum { kX, kY, kScratch, kSlots };

constexpr double kTimeStep = 1.0 / 30.0;

std::unique_ptr<Backend> makeBackend(const SceneData& data, const Forcing& forcing, BackendChoice choice) {
  if (choice == BackendChoice::Cpu) return makeCpuBackend(data, forcing, kSlots);
  return makeOpenCLBackend(data, forcing, kSlots, optionsFor(choice, Integrator::BackwardEuler).opencl);
}

/// The solve's coefficient c per integrator, as its steps take it (solveCoefficient).
double solveConstant(Integrator integrator) {
  switch (integrator) {
    case Integrator::ImplicitMidpoint: return solveCoefficient(ImplicitSolve::Midpoint, kTimeStep);
    case Integrator::BDF2: return solveCoefficient(ImplicitSolve::Bdf2, kTimeStep);
    default: return solveCoefficient(ImplicitSolve::BackwardEuler, kTimeStep);
  }
}

/// Inertial target: one step of free fall from the rest shape, with a smooth perturbation of
/// about 1 % of the body size so that every element projects non-trivially.
Eigen::MatrixX3d inertialTarget(const Scene& s) {
  Eigen::MatrixX3d y = s.positions;
  for (Eigen::Index j = 0; j < y.rows(); ++j) {
    const Eigen::Vector3d p = s.positions.row(j).transpose();
    y.row(j) += (kTimeStep * kTimeStep * s.gravity).transpose();
    y(j, 0) += 0.01 * std::sin(7.0 * p.y() + 3.0 * p.z());
    y(j, 2) += 0.01 * std::cos(5.0 * p.x() + 2.0 * p.y());
  }
  return y;
}

struct IterationFixture {
  IterationFixture(const Scene& s, BackendChoice choice, double c_, int cg_iterations = 0)
      : scene(s),
        data(s),
        backend(makeBackend(data, forcing, choice)),
        system(data),
        solver(*backend, system, kScratch),
        c(c_) {
    if (cg_iterations > 0) {
      control.global_solve = GlobalSolve::ConjugateGradient;
      control.cg_iterations = cg_iterations;
    }
    const Eigen::MatrixX3d y = inertialTarget(s);
    backend->write(kY, y);
    backend->write(kX, y);
    // First solves: the factorization of K_c and the first kernel launches.
    solver.solve(c, kY, kX, kTimeStep, control);
    solver.solve(c, kY, kX, kTimeStep, control);
  }
  Scene scene;
  SceneData data;
  Forcing forcing{data.scene()};
  std::unique_ptr<Backend> backend;
  GlobalSystem system;
  LocalGlobalSolver solver;
  double c;
  IterationControl control = IterationControl::plain(1);  // exactly one iteration, no objective tracking
};

void runIteration(benchmark::State& state, const std::string& key, const std::function<Scene()>& make_scene,
                  BackendChoice choice, Integrator integrator) {
  if (const std::string why = skipReason(choice); !why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  IterationFixture* fixture = nullptr;
  try {
    fixture = &cachedFixture<IterationFixture>(
        key, [&] { return std::make_unique<IterationFixture>(make_scene(), choice, solveConstant(integrator)); });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  IterationFixture& f = *fixture;
  f.backend->times() = PhaseTimes{};
  double iterations = 0;
  for (auto _ : state) iterations += f.solver.solve(f.c, kY, kX, kTimeStep, f.control);
  setSizeCounters(state, f.scene);
  setPhaseCounters(state, f.backend->times());
  state.counters["iterations"] = benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
  state.SetLabel(f.backend->description());
}

/// One frame's BE solve (10 iterations from y) with `control`'s global solve on `backend`.
Eigen::MatrixX3d frameSolve(Backend& backend, const SceneData& data, const Scene& s, IterationControl control) {
  GlobalSystem system(data);
  LocalGlobalSolver solver(backend, system, kScratch);
  const Eigen::MatrixX3d y = inertialTarget(s);
  backend.write(kY, y);
  backend.write(kX, y);
  control.iterations = control.max_iterations = 10;
  solver.solve(solveConstant(Integrator::BackwardEuler), kY, kX, kTimeStep, control);
  Eigen::MatrixX3d x;
  backend.read(kX, x);
  return x;
}

void runGlobalSolve(benchmark::State& state, const std::string& key, const SceneCase& scene, BackendChoice choice,
                    int cg_iterations) {
  if (const std::string why = skipReason(choice); !why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  IterationFixture* fixture = nullptr;
  try {
    fixture = &cachedFixture<IterationFixture>(key, [&] {
      return std::make_unique<IterationFixture>(scene.make(), choice, solveConstant(Integrator::BackwardEuler),
                                                cg_iterations);
    });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  IterationFixture& f = *fixture;
  f.backend->times() = PhaseTimes{};
  for (auto _ : state) f.solver.solve(f.c, kY, kX, kTimeStep, f.control);
  setSizeCounters(state, f.scene);
  setPhaseCounters(state, f.backend->times());
  // Accuracy, outside the timed loop: the frame's result against the CPU factor's.
  auto cpu = makeCpuBackend(f.data, f.forcing, kSlots);
  const Eigen::MatrixX3d reference = frameSolve(*cpu, f.data, f.scene, IterationControl::plain(10));
  const Eigen::MatrixX3d x = frameSolve(*f.backend, f.data, f.scene, f.control);
  const double size = (f.scene.positions.colwise().maxCoeff() - f.scene.positions.colwise().minCoeff()).norm();
  state.counters["position_error"] = (x - reference).cwiseAbs().maxCoeff() / size;
  state.SetLabel(f.backend->description());
}

/// The rotations' inputs: F = Ds Dm^-1 of every tet of `s` at the positions of
/// inertialTarget(s), and each tet's rotation at the rest shape (a warm start's previous state).
struct TetDeformations {
  std::vector<Eigen::Matrix3d> f;
  std::vector<Eigen::Quaterniond> previous;
};

TetDeformations tetDeformations(const Scene& s) {
  const Eigen::MatrixX3d y = inertialTarget(s);
  TetDeformations out;
  for (const Tet& tet : s.tets) {
    Eigen::Matrix3d ds, ds_rest, dm;
    for (int k = 0; k < 3; ++k) {
      ds.col(k) = (y.row(tet.vertices[k + 1]) - y.row(tet.vertices[0])).transpose();
      ds_rest.col(k) = (s.positions.row(tet.vertices[k + 1]) - s.positions.row(tet.vertices[0])).transpose();
      dm.col(k) = (s.rest_positions.row(tet.vertices[k + 1]) - s.rest_positions.row(tet.vertices[0])).transpose();
    }
    out.f.push_back(ds * dm.inverse());
    out.previous.emplace_back(projections::nearestRotation(Eigen::Matrix3d(ds_rest * dm.inverse())));
  }
  return out;
}

enum class RotationMethod { NewtonPolar, NewtonPolarLanes, JacobiSvd, WarmQuaternion };

/// One step of Mueller et al. 2016 ("A robust method to extract the rotational part of
/// deformations") from q: q <- exp(w) q with w = sum_i r_i x f_i / |sum_i r_i . f_i|.
Eigen::Quaterniond quaternionStep(const Eigen::Matrix3d& f, const Eigen::Quaterniond& q) {
  const Eigen::Matrix3d r = q.toRotationMatrix();
  const Eigen::Vector3d w = (r.col(0).cross(f.col(0)) + r.col(1).cross(f.col(1)) + r.col(2).cross(f.col(2))) /
                            (std::abs(r.col(0).dot(f.col(0)) + r.col(1).dot(f.col(1)) + r.col(2).dot(f.col(2))) + 1e-9);
  const double angle = w.norm();
  if (angle < 1e-15) return q;
  return (Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle)) * q).normalized();
}

void runRotations(benchmark::State& state, const TetDeformations& input, RotationMethod method) {
  const std::size_t count = input.f.size();
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d r;
  constexpr int W = projections::kLanes;
  for (auto _ : state) {
    if (method == RotationMethod::NewtonPolarLanes) {
      // The CPU reference's passes: kLanes matrices side by side (projections::nearestRotations).
      for (std::size_t e = 0; e + W <= count; e += W) {
        double m[9][W], rl[9][W];
        for (int l = 0; l < W; ++l)
          for (int i = 0; i < 9; ++i) m[i][l] = input.f[e + std::size_t(l)].data()[i];
        projections::nearestRotations(m, rl);
        for (int l = 0; l < W; ++l)
          for (int i = 0; i < 9; ++i) sum.data()[i] += rl[i][l];
      }
      benchmark::DoNotOptimize(sum);
      continue;
    }
    for (std::size_t e = 0; e < count; ++e) {
      switch (method) {
        case RotationMethod::NewtonPolarLanes:
        case RotationMethod::NewtonPolar: projections::nearestRotation(input.f[e].data(), r.data()); break;
        case RotationMethod::JacobiSvd: r = projections::nearestRotationBySvd(input.f[e]); break;
        case RotationMethod::WarmQuaternion:
          r = quaternionStep(input.f[e], input.previous[e]).toRotationMatrix();
          break;
      }
      sum += r;
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(count));
  double max_error = 0.0;
  for (std::size_t e = 0; e < count; ++e) {
    const Eigen::Matrix3d exact = projections::nearestRotationBySvd(input.f[e]);
    if (method == RotationMethod::NewtonPolar || method == RotationMethod::NewtonPolarLanes)
      projections::nearestRotation(input.f[e].data(), r.data());
    if (method == RotationMethod::JacobiSvd) r = exact;
    if (method == RotationMethod::WarmQuaternion) r = quaternionStep(input.f[e], input.previous[e]).toRotationMatrix();
    max_error = std::max(max_error, (r - exact).norm());
  }
  state.counters["max_error"] = max_error;
}

}  // namespace

void registerIterationCases() {
  for (const SceneCase& scene : referenceScenes()) {
    if (scene.make().tets.empty()) continue;
    for (const auto& [label, method] : {std::pair{"newton-polar", RotationMethod::NewtonPolar},
                                        std::pair{"newton-polar-lanes", RotationMethod::NewtonPolarLanes},
                                        std::pair{"jacobi-svd", RotationMethod::JacobiSvd},
                                        std::pair{"warm-quaternion-1", RotationMethod::WarmQuaternion}}) {
      const std::string name = "rotation/" + scene.name + "/" + label;
      const SceneCase c = scene;
      const RotationMethod m = method;
      benchmark::RegisterBenchmark(name.c_str(),
                                   [c, m](benchmark::State& state) {
                                     const TetDeformations& input = cachedFixture<TetDeformations>(
                                         "rotation/" + c.name,
                                         [&] { return std::make_unique<TetDeformations>(tetDeformations(c.make())); });
                                     runRotations(state, input, m);
                                   })
          ->UseRealTime()
          ->Unit(benchmark::kMicrosecond);
    }
  }
  for (const SceneCase& scene : referenceScenes())
    for (Integrator integrator : {Integrator::BackwardEuler, Integrator::BDF2, Integrator::ImplicitMidpoint})
      for (BackendChoice backend : allBackends()) {
        const std::string name =
            "iteration/" + scene.name + "/" + integratorName(integrator) + "/" + backendLabel(backend);
        benchmark::RegisterBenchmark(
            name.c_str(), [=](benchmark::State& state) { runIteration(state, name, scene.make, backend, integrator); })
            ->UseRealTime()
            ->Unit(benchmark::kMicrosecond);
      }

  // Factor (cg = 0) against the CG global step (GlobalSolve::ConjugateGradient), per iteration,
  // with the accuracy counter; run interleaved (docs/benchmarks.md "Global solve on the device").
  auto registerGlobalStep = [](const std::string& family, const SceneCase& scene, std::initializer_list<int> cgs) {
    for (const int cg : cgs)
      for (BackendChoice backend : allBackends()) {
        const std::string name = family + "/" + scene.name + "/" +
                                 (cg == 0 ? std::string("factor") : "cg" + std::to_string(cg)) + "/" +
                                 backendLabel(backend);
        benchmark::RegisterBenchmark(name.c_str(),
                                     [=](benchmark::State& state) { runGlobalSolve(state, name, scene, backend, cg); })
            ->UseRealTime()
            ->Unit(benchmark::kMicrosecond);
      }
  };
  for (const SceneCase& scene : referenceScenes()) registerGlobalStep("global_step", scene, {0, 5, 10, 20, 40});
  // The same on the tet bars of growing size of autoRuleScenes(): where the device CG's O(n)
  // iterations overtake the factor's solve, whose fill (and cost) grows faster than n in 3-D.
  for (const SceneCase& scene : autoRuleScenes())
    if (scene.name.rfind("tetbar", 0) == 0) registerGlobalStep("global_step_scaling", scene, {0, 10});
  for (BackendChoice backend : allBackends()) {
    const std::string name = std::string("scaling_iteration/cloth/BE/") + backendLabel(backend);
    auto* b = benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& state) {
      const int side = static_cast<int>(state.range(0));
      runIteration(
          state, name + "/" + std::to_string(side), [side] { return clothScene(side); }, backend,
          Integrator::BackwardEuler);
    });
    for (int side : scalingSides()) b->Arg(side);
    b->ArgName("side")->UseRealTime()->Unit(benchmark::kMicrosecond);
  }

  // BackendKind::Auto's rule: one BE iteration per backend on spring and triangle cloths and tet
  // bars of growing size (run with --benchmark_enable_random_interleaving so the backends of a
  // scene see the same load; docs/benchmarks.md "Auto backend rule").
  for (const SceneCase& scene : autoRuleScenes())
    for (BackendChoice backend : allBackends()) {
      const std::string name = "auto_iteration/" + scene.name + "/BE/" + backendLabel(backend);
      benchmark::RegisterBenchmark(
          name.c_str(),
          [=](benchmark::State& state) { runIteration(state, name, scene.make, backend, Integrator::BackwardEuler); })
          ->UseRealTime()
          ->Unit(benchmark::kMicrosecond);
    }
}

}  // namespace stabint::bench
