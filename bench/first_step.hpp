#pragma once
// The fixture of the cases that time one phase alone (a local step, an energy pass, the host
// solve): a backend and the factored global system at a scene's first BE step, x = y = x_0 + h^2 g.
#include "bench_common.hpp"

#include "backend/backend.hpp"
#include "cpu/cpu_backend.hpp"
#include "opencl/opencl_backend.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"

#include <Eigen/Core>

#include <memory>

namespace stabint::bench::first_step {

enum { kX, kY, kSlots };
constexpr double kTimeStep = 1.0 / 30.0;
constexpr double kC = 1.0 / (kTimeStep * kTimeStep);

struct Fixture {
  Fixture(const Scene& s, BackendChoice choice)
      : scene(s),
        data(s),
        backend(choice == BackendChoice::Cpu
                    ? makeCpuBackend(data, forcing, kSlots)
                    : makeOpenCLBackend(data, forcing, kSlots, optionsFor(choice, Integrator::BackwardEuler).opencl)),
        system(data) {
    Eigen::MatrixX3d y = s.positions;
    for (Eigen::Index j = 0; j < y.rows(); ++j) y.row(j) += (kTimeStep * kTimeStep * s.gravity).transpose();
    backend->write(kY, y);
    backend->write(kX, y);
    backend->localStepRhs(kX, kY, kC, kTimeStep, rhs);
    system.solve(kC, rhs, x);  // factors
  }
  Scene scene;
  SceneData data;
  Forcing forcing{data.scene()};
  std::unique_ptr<Backend> backend;
  GlobalSystem system;
  Eigen::MatrixX3d rhs, x;
};

}  // namespace stabint::bench::first_step
