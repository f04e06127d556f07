// The CPU side's threads (host/common/worker_pool.hpp, docs/method.md "Threads on the CPU"): the
// CPU reference's element passes and the host solve give the same results bit for bit on one
// thread and on several, on scenes whose passes take a threaded path (by the library's choice,
// and each path forced: host/cpu/cpu_backend.hpp, ThreadedPassPath) with every element type and
// the blocks after them that stay on one thread (contact, pins).
#include "contact_scenes.hpp"
#include "cpu/cpu_backend.hpp"
#include "common/worker_pool.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"

#include <stabint/stabint.hpp>

#include <Eigen/CholmodSupport>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <numeric>
#include <random>
#include <thread>
#include <vector>

namespace stabint {
namespace {

class ThreadCount {
 public:
  explicit ThreadCount(int threads) : previous_(cpuThreads()) { setCpuThreads(threads); }
  ~ThreadCount() { setCpuThreads(previous_); }

 private:
  int previous_;
};

class PathCount {
 public:
  explicit PathCount(ThreadedPassPath path) : previous_(threadedPassPath()) { setThreadedPassPath(path); }
  ~PathCount() { setThreadedPassPath(previous_); }

 private:
  ThreadedPassPath previous_;
};

struct Run {
  Eigen::MatrixX3d x, v;
  std::vector<double> energies;
  std::vector<int> branches;
};

Run runWith(const Scene& scene, Integrator integrator, int threads, int steps) {
  ThreadCount setting(threads);
  SimulatorOptions options;
  options.integrator = integrator;
  options.time_step = 1.0 / 60.0;
  Simulator sim(scene, options);
  Run run;
  for (int i = 0; i < steps; ++i) {
    const StepReport& r = sim.step();
    run.energies.push_back(r.energy.total());
    run.energies.push_back(r.target);
    run.branches.push_back(static_cast<int>(r.branch));
  }
  run.x = sim.positions();
  run.v = sim.velocities();
  return run;
}

// Bit for bit: == on every entry (a tolerance would hide a changed order of additions).
void expectSameRun(const Run& one, const Run& many) {
  ASSERT_EQ(one.x.rows(), many.x.rows());
  for (Eigen::Index i = 0; i < one.x.size(); ++i) {
    ASSERT_EQ(one.x.data()[i], many.x.data()[i]) << "position entry " << i;
    ASSERT_EQ(one.v.data()[i], many.v.data()[i]) << "velocity entry " << i;
  }
  EXPECT_EQ(one.energies, many.energies);
  EXPECT_EQ(one.branches, many.branches);
}

// A pinned tet bar of 2,880 tets (on threads by the library's choice) swinging down under gravity
// onto a ground plane: tets in the threaded part, contact and pins after it.
Scene barOnGround() {
  TetBarParams p;
  p.nx = 24;
  p.ny = 4;
  p.nz = 4;
  Scene s = makeTetBar(p);
  s.colliders.push_back(testing::groundPlane(s.positions.col(1).minCoeff() - 0.05, 1e4));
  return s;
}

// A 40 x 40 triangle cloth (triangle strain and bending hinges, 3,042 + 4,485 elements: on
// threads by the library's choice) with pinned corners falling onto a sphere.
Scene triangleClothOnSphere() {
  ClothGridParams p;
  p.nx = 40;
  p.ny = 40;
  p.model = ClothModel::Triangles;
  Scene s = makeClothGrid(p);
  s.colliders.push_back(testing::sphereCollider(Eigen::Vector3d(0.5, 0.3, 0.2), 0.2, 1e4));
  return s;
}

// The scene with its particles renumbered at random: every element then has vertices far apart
// in the numbering, so the Owned path's vertex ranges cut through most elements (runs of one
// element, elements computed on several threads).
Scene shuffled(const Scene& scene, unsigned seed) {
  const int n = scene.numParticles();
  std::vector<int> to(static_cast<std::size_t>(n));  // old index -> new
  std::iota(to.begin(), to.end(), 0);
  std::shuffle(to.begin(), to.end(), std::mt19937(seed));
  Scene s = scene;
  for (int i = 0; i < n; ++i) {
    const int j = to[static_cast<std::size_t>(i)];
    s.rest_positions.row(j) = scene.rest_positions.row(i);
    s.positions.row(j) = scene.positions.row(i);
    s.velocities.row(j) = scene.velocities.row(i);
    s.masses[j] = scene.masses[i];
  }
  auto map = [&](int& v) { v = to[static_cast<std::size_t>(v)]; };
  for (Spring& e : s.springs) map(e.a), map(e.b);
  for (Tet& e : s.tets)
    for (int& v : e.vertices) map(v);
  for (TriangleStrain& e : s.triangle_strains)
    for (int& v : e.vertices) map(v);
  for (BendingHinge& e : s.bending_hinges)
    for (int& v : e.vertices) map(v);
  for (Pin& e : s.pins) map(e.vertex);
  for (Body& b : s.bodies)
    for (int& v : b.particles) map(v);
  for (auto& t : s.triangles)
    for (int& v : t) map(v);
  validateScene(s);
  return s;
}

// What one pass of each kind gives: the local step's right-hand side with and without the
// energy, its gradient form with the energy (L-BFGS's), the forces, and an energy pass.
struct PassResults {
  Eigen::MatrixX3d rhs, rhs_energy, gradient, accelerations;
  PotentialEnergy at_x, gradient_at_x, potential;
};

PassResults passResults(const Scene& scene, const Eigen::MatrixX3d& x) {
  const SceneData data(scene);
  Forcing forcing(data.scene());
  auto backend = makeCpuBackend(data, forcing, 2);
  backend->write(0, x);
  backend->write(1, scene.positions);
  PassResults r;
  backend->localStepRhs(0, 1, 900.0, 0.0, r.rhs, nullptr);
  backend->localStepRhs(0, 1, 900.0, 0.0, r.rhs_energy, &r.at_x);
  backend->localStepGradient(0, 1, 900.0, 0.0, r.gradient, &r.gradient_at_x);
  backend->accelerations(1, 0, 0.0);
  backend->read(1, r.accelerations);
  r.potential = backend->potential(0, 0.0);
  return r;
}

void expectSameMatrix(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b, const char* what) {
  ASSERT_EQ(a.rows(), b.rows()) << what;
  for (Eigen::Index i = 0; i < a.size(); ++i) ASSERT_EQ(a.data()[i], b.data()[i]) << what << " entry " << i;
}

void expectSameEnergy(const PotentialEnergy& a, const PotentialEnergy& b, const char* what) {
  EXPECT_EQ(a.internal, b.internal) << what;
  EXPECT_EQ(a.pins, b.pins) << what;
  EXPECT_EQ(a.external, b.external) << what;
}

// Every threaded path, forced whatever the size, on 2 and 3 threads gives each pass of the
// single-threaded one bit for bit: spring and triangle cloths on a sphere (contact and pins after
// the threaded blocks), a tet bar, and the same scenes renumbered at random.
TEST(CpuThreads, EveryThreadedPathGivesTheSerialPassBitForBit) {
  ClothGridParams springs;
  springs.nx = springs.ny = 24;
  ClothGridParams triangles;
  triangles.nx = triangles.ny = 16;
  triangles.model = ClothModel::Triangles;
  TetBarParams bar;
  bar.nx = 10;
  bar.ny = bar.nz = 3;
  std::vector<Scene> scenes;
  for (const ClothGridParams& p : {springs, triangles}) {
    Scene s = makeClothGrid(p);
    s.colliders.push_back(testing::sphereCollider(Eigen::Vector3d(0.5, 0.5, 0.0), 0.2, 1e4));
    scenes.push_back(s);
  }
  scenes.push_back(makeTetBar(bar));
  for (std::size_t i = 0, count = scenes.size(); i < count; ++i)
    scenes.push_back(shuffled(scenes[i], 7u + unsigned(i)));
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const Scene& scene = scenes[i];
    // Deformed positions, some inside the sphere (contact elements active).
    std::mt19937 rng(11u + unsigned(i));
    std::uniform_real_distribution<double> offset(-0.02, 0.02);
    Eigen::MatrixX3d x = scene.positions;
    for (Eigen::Index j = 0; j < x.size(); ++j) x.data()[j] += offset(rng);
    PassResults serial;
    {
      ThreadCount one(1);
      serial = passResults(scene, x);
    }
    for (ThreadedPassPath path : {ThreadedPassPath::Buffered, ThreadedPassPath::Owned})
      for (int threads : {2, 3}) {
        SCOPED_TRACE("scene " + std::to_string(i) + (path == ThreadedPassPath::Owned ? " owned " : " buffered ") +
                     std::to_string(threads) + " threads");
        ThreadCount setting(threads);
        PathCount forced(path);
        const PassResults r = passResults(scene, x);
        EXPECT_EQ(lastPassPath(), path);
        expectSameMatrix(serial.rhs, r.rhs, "local step");
        expectSameMatrix(serial.rhs_energy, r.rhs_energy, "local step with energy");
        expectSameMatrix(serial.gradient, r.gradient, "local step's gradient with energy");
        expectSameEnergy(serial.gradient_at_x, r.gradient_at_x, "gradient step's energy");
        expectSameMatrix(serial.accelerations, r.accelerations, "accelerations");
        expectSameEnergy(serial.at_x, r.at_x, "local step's energy");
        expectSameEnergy(serial.potential, r.potential, "energy pass");
      }
  }
}

// Whole runs with the Owned path forced (the library's choice takes it on large cloths): the same
// bit for bit as on one thread.
TEST(CpuThreads, OwnedPathRunsAreTheSameOnOneAndTwoThreads) {
  PathCount forced(ThreadedPassPath::Owned);
  const Scene bar = barOnGround();
  expectSameRun(runWith(bar, Integrator::EnergyBlend, 1, 6), runWith(bar, Integrator::EnergyBlend, 2, 6));
  const Scene cloth = triangleClothOnSphere();
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::SymplecticEuler}) {
    SCOPED_TRACE(integratorName(integrator));
    expectSameRun(runWith(cloth, integrator, 1, 6), runWith(cloth, integrator, 2, 6));
  }
}

TEST(CpuThreads, BlendOnTetBarIsTheSameBitForBitOnOneAndTwoThreads) {
  const Scene scene = barOnGround();
  expectSameRun(runWith(scene, Integrator::EnergyBlend, 1, 12), runWith(scene, Integrator::EnergyBlend, 2, 12));
}

TEST(CpuThreads, BackwardEulerOnTetBarIsTheSameOnOneAndThreeThreads) {
  const Scene scene = barOnGround();
  expectSameRun(runWith(scene, Integrator::BackwardEuler, 1, 6), runWith(scene, Integrator::BackwardEuler, 3, 6));
}

TEST(CpuThreads, TriangleClothIsTheSameOnOneAndTwoThreads) {
  const Scene scene = triangleClothOnSphere();
  for (Integrator integrator : {Integrator::EnergyBlend, Integrator::SymplecticEuler}) {
    SCOPED_TRACE(integratorName(integrator));
    expectSameRun(runWith(scene, integrator, 1, 8), runWith(scene, integrator, 2, 8));
  }
}

// A batch large enough for its per-scene passes and its L-BFGS history passes to go on threads
// (runs of scenes per thread: cpu_backend.cpp segmentPasses, lbfgs.cpp forEachSegment) steps
// bit for bit as on one thread, with BE and with the blend (whose energy passes are per scene).
TEST(CpuThreads, LargeBatchIsTheSameOnOneAndTwoThreads) {
  ClothGridParams p;
  p.nx = p.ny = 10;
  std::vector<Scene> scenes(150, makeClothGrid(p));  // 15,000 particles
  for (std::size_t s = 0; s < scenes.size(); ++s) scenes[s].velocities.col(2).setConstant(0.01 * double(s % 7));
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend}) {
    SCOPED_TRACE(integratorName(integrator));
    SimulatorOptions options;
    options.integrator = integrator;
    auto run = [&](int threads) {
      ThreadCount setting(threads);
      BatchSimulator batch(scenes, options);
      for (int i = 0; i < 4; ++i) batch.step();
      std::vector<Eigen::MatrixX3d> x;
      for (int s = 0; s < batch.size(); ++s) x.push_back(batch.positions(s));
      return x;
    };
    const std::vector<Eigen::MatrixX3d> one = run(1), two = run(2);
    ASSERT_EQ(one.size(), two.size());
    for (std::size_t s = 0; s < one.size(); ++s) ASSERT_EQ(one[s], two[s]) << "scene " << s;
    EXPECT_NE(one[0], scenes[0].positions);
  }
}

// The host solve (one pass over the factor for the three columns, on the calling thread) gives
// the same result bit for bit on one thread and on two, and CHOLMOD's solve to round-off.
TEST(CpuThreads, GlobalSolveIsTheSameOnOneAndTwoThreads) {
  TetBarParams p;
  p.nx = 40;
  p.ny = 6;
  p.nz = 6;
  const Scene scene = makeTetBar(p);
  const SceneData data(scene);
  GlobalSystem system(data);
  const double c = 3600.0;
  Eigen::SparseMatrix<double> k = system.stiffnessLaplacian();
  for (Eigen::Index j = 0; j < k.rows(); ++j) k.coeffRef(j, j) += c * system.masses()[j];
  Eigen::CholmodSimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> one;
  one.compute(k);
  ASSERT_EQ(one.info(), Eigen::Success);
  const Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Random(scene.numParticles(), 3);
  const Eigen::MatrixX3d cholmod = one.solve(rhs);
  Eigen::MatrixX3d first;
  for (int threads : {1, 2}) {
    ThreadCount setting(threads);
    Eigen::MatrixX3d x;
    system.solve(c, rhs, x);
    ASSERT_EQ(x.rows(), rhs.rows());
    EXPECT_LT((x - cholmod).norm(), 1e-12 * cholmod.norm()) << threads << " threads";
    if (threads == 1) {
      first = x;
      continue;
    }
    for (Eigen::Index i = 0; i < x.size(); ++i) ASSERT_EQ(x.data()[i], first.data()[i]) << threads << " threads";
  }
}

// From GlobalSystem::kSubtreeRows particles the solve's backward pass runs over two subtrees on
// two threads: the same bit for bit on one thread and on two, before and after a rank update
// (which turns the factor into LDL' and may change its elimination tree).
TEST(CpuThreads, SubtreeSolveIsTheSameOnOneAndTwoThreads) {
  ClothGridParams p;
  p.nx = p.ny = 125;  // 15,625 particles
  const Scene scene = makeClothGrid(p);
  ASSERT_GE(scene.numParticles(), GlobalSystem::kSubtreeRows);
  const SceneData data(scene);
  GlobalSystem system(data);
  const double c = 900.0;
  const Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Random(scene.numParticles(), 3);
  for (int round = 0; round < 2; ++round) {
    Eigen::SparseMatrix<double> k = system.stiffnessLaplacian();
    for (Eigen::Index j = 0; j < k.rows(); ++j) k.coeffRef(j, j) += c * system.masses()[j];
    Eigen::CholmodSimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> fresh;
    fresh.compute(k);
    ASSERT_EQ(fresh.info(), Eigen::Success);
    const Eigen::MatrixX3d expected = fresh.solve(rhs);
    Eigen::MatrixX3d x[2];
    for (int threads : {1, 2}) {
      ThreadCount setting(threads);
      system.solve(c, rhs, x[threads - 1]);
    }
    EXPECT_LT((x[0] - expected).norm(), 1e-10 * expected.norm()) << "round " << round;
    for (Eigen::Index i = 0; i < x[0].size(); ++i) ASSERT_EQ(x[0].data()[i], x[1].data()[i]) << "round " << round;
    system.addToDiagonal(std::vector<int>{17, 4000, 9000}, std::vector<double>{50.0, 80.0, 120.0});
  }
}

TEST(CpuThreads, ParallelForRunsEveryTaskOnceWhateverTheThreadCount) {
  for (int threads : {1, 2, 4}) {
    ThreadCount setting(threads);
    for (int tasks : {0, 1, 2, 7, 1000}) {
      std::vector<std::atomic<int>> runs(static_cast<std::size_t>(tasks));
      parallelFor(tasks, [&](int i) { runs[static_cast<std::size_t>(i)].fetch_add(1); });
      for (int i = 0; i < tasks; ++i) EXPECT_EQ(runs[static_cast<std::size_t>(i)].load(), 1) << tasks << " tasks";
    }
  }
}

// Two simulators stepped from two threads at once share the pool: one of the calls runs on its
// own thread, and both still finish every task.
TEST(CpuThreads, ConcurrentCallsFromTwoThreadsBothComplete) {
  ThreadCount setting(2);
  std::atomic<long> sum{0};
  auto caller = [&] {
    for (int round = 0; round < 200; ++round) parallelFor(16, [&](int i) { sum.fetch_add(i + 1); });
  };
  std::thread other(caller);
  caller();
  other.join();
  EXPECT_EQ(sum.load(), 2L * 200 * (16 * 17 / 2));
}

TEST(CpuThreads, SettingIsAtLeastOne) {
  ThreadCount setting(0);
  EXPECT_EQ(cpuThreads(), 1);
}

}  // namespace
}  // namespace stabint
