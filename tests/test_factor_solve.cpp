// solveSimplicial (host/solver/factor_solve.hpp), the global step's triangular solves over
// CHOLMOD's simplicial factor: CHOLMOD's own solve to round-off on the LL' factor as factored and
// on the LDL' factor that cholmod_updown leaves, and the same bit for bit whatever the lanes
// (three columns as {x, y, z, 0}, or as {x, y} and {z, 0}).
#include "common/worker_pool.hpp"
#include "scene/scene_batch.hpp"
#include "scene/scene_data.hpp"
#include "solver/factor_solve.hpp"
#include "solver/global_system.hpp"

#include <stabint/stabint.hpp>

#include <Eigen/CholmodSupport>
#include <gtest/gtest.h>

#include <vector>

namespace stabint {
namespace {

struct Factored {
  explicit Factored(const Eigen::SparseMatrix<double>& k) {
    cholmod_start(&common);
    common.print = 0;
    common.supernodal = CHOLMOD_SIMPLICIAL;
    common.final_ll = 1;
    cholmod_sparse a =
        Eigen::viewAsCholmod(Eigen::Ref<Eigen::SparseMatrix<double>>(const_cast<Eigen::SparseMatrix<double>&>(k)));
    a.stype = -1;
    factor = cholmod_analyze(&a, &common);
    cholmod_factorize(&a, factor, &common);
  }
  ~Factored() {
    cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
  Factored(const Factored&) = delete;
  Factored& operator=(const Factored&) = delete;
  Eigen::MatrixX3d cholmodSolve(const Eigen::MatrixX3d& rhs) {
    cholmod_dense b{};
    b.nrow = static_cast<std::size_t>(rhs.rows());
    b.ncol = 3;
    b.nzmax = b.nrow * 3;
    b.d = b.nrow;
    b.x = const_cast<double*>(rhs.data());
    b.xtype = CHOLMOD_REAL;
    b.dtype = CHOLMOD_DOUBLE;
    cholmod_dense* x = cholmod_solve(CHOLMOD_A, factor, &b, &common);
    Eigen::MatrixX3d out = Eigen::Map<const Eigen::MatrixX3d>(static_cast<const double*>(x->x), rhs.rows(), 3);
    cholmod_free_dense(&x, &common);
    return out;
  }
  cholmod_common common;
  cholmod_factor* factor = nullptr;
};

Eigen::SparseMatrix<double> systemOf(const Scene& scene, double c) {
  const SceneData data(scene);
  const GlobalSystem system(data);
  Eigen::SparseMatrix<double> k = system.stiffnessLaplacian();
  for (Eigen::Index j = 0; j < k.rows(); ++j) k.coeffRef(j, j) += c * system.masses()[j];
  k.makeCompressed();
  return k;
}

void expectSolvesAsCholmod(Factored& f, const Eigen::MatrixX3d& rhs) {
  ASSERT_TRUE(simplicialSolveApplies(*f.factor));
  const Eigen::MatrixX3d expected = f.cholmodSolve(rhs);
  const std::size_t n = static_cast<std::size_t>(rhs.rows());
  std::vector<double> work;
  Eigen::MatrixX3d one(rhs.rows(), 3), groups(rhs.rows(), 3);
  solveSimplicial(*f.factor, rhs.data(), one.data(), n, 0, 3, 4, work);
  solveSimplicial(*f.factor, rhs.data(), groups.data(), n, 0, 2, 2, work);
  solveSimplicial(*f.factor, rhs.data(), groups.data(), n, 2, 1, 2, work);
  EXPECT_LT((one - expected).norm(), 1e-12 * expected.norm());
  for (Eigen::Index i = 0; i < one.size(); ++i) ASSERT_EQ(one.data()[i], groups.data()[i]) << i;
}

TEST(FactorSolve, ClothAndTetBarAsCholmodOnTheLLFactor) {
  TetBarParams bar;
  bar.nx = 20;
  bar.ny = 4;
  bar.nz = 4;
  ClothGridParams cloth;
  cloth.nx = cloth.ny = 30;
  for (const Scene& scene : {makeTetBar(bar), makeClothGrid(cloth)}) {
    Factored f(systemOf(scene, 900.0));
    ASSERT_EQ(f.common.status, CHOLMOD_OK);
    ASSERT_TRUE(f.factor->is_ll);
    expectSolvesAsCholmod(f, Eigen::MatrixX3d::Random(scene.numParticles(), 3));
  }
}

// cholmod_updown turns the LL' factor into LDL' (unit L, D on the diagonal), with columns that
// may no longer be packed: the solve reads that too.
TEST(FactorSolve, AsCholmodOnTheUpdatedLDLFactor) {
  TetBarParams bar;
  bar.nx = 20;
  bar.ny = 4;
  bar.nz = 4;
  const Scene scene = makeTetBar(bar);
  Factored f(systemOf(scene, 900.0));
  const int n = static_cast<int>(f.factor->n);
  cholmod_sparse* c = cholmod_allocate_sparse(n, 2, 2, 1, 1, 0, CHOLMOD_REAL, &f.common);
  int* cp = static_cast<int*>(c->p);
  int* ci = static_cast<int*>(c->i);
  double* cx = static_cast<double*>(c->x);
  cp[0] = 0;
  cp[1] = 1;
  cp[2] = 2;
  ci[0] = 3;
  ci[1] = n / 2;
  cx[0] = 1e3;
  cx[1] = 2e2;
  ASSERT_TRUE(cholmod_updown(1, c, f.factor, &f.common));
  cholmod_free_sparse(&c, &f.common);
  ASSERT_FALSE(f.factor->is_ll);
  expectSolvesAsCholmod(f, Eigen::MatrixX3d::Random(scene.numParticles(), 3));
}

// The variant with the backward pass over two subtrees on two threads (measured in
// bench/bench_solver.cpp): CHOLMOD's solve to round-off, the same bit for bit on one thread and
// on two.
TEST(FactorSolve, SubtreeSplitIsTheSameOnOneAndTwoThreads) {
  ClothGridParams cloth;
  cloth.nx = cloth.ny = 40;
  const Scene scene = makeClothGrid(cloth);
  Factored f(systemOf(scene, 900.0));
  const SubtreeSplit split = findSubtreeSplit(*f.factor);
  ASSERT_GT(split.a_end, 0);
  ASSERT_GT(split.b_end, split.a_end);
  const Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Random(scene.numParticles(), 3);
  const Eigen::MatrixX3d expected = f.cholmodSolve(rhs);
  const std::size_t n = static_cast<std::size_t>(rhs.rows());
  std::vector<double> work;
  Eigen::MatrixX3d x[2] = {Eigen::MatrixX3d(rhs.rows(), 3), Eigen::MatrixX3d(rhs.rows(), 3)};
  const int previous = cpuThreads();
  for (int threads : {1, 2}) {
    setCpuThreads(threads);
    solveSimplicialSubtrees(*f.factor, split, rhs.data(), x[threads - 1].data(), n, work);
  }
  setCpuThreads(previous);
  EXPECT_LT((x[0] - expected).norm(), 1e-12 * expected.norm());
  for (Eigen::Index i = 0; i < x[0].size(); ++i) ASSERT_EQ(x[0].data()[i], x[1].data()[i]) << i;
}

// A batch's factor is a forest, one tree per scene (no element couples two scenes): its trees on
// threads (solveSimplicialForest, GlobalSystem::solve's path for batches) give the serial solve's
// result bit for bit on 1, 2 and 3 threads, and CHOLMOD's to round-off, on a mixed batch of cloths
// of three sizes, chains and tet bars, before and after a rank update (an LDL' factor).
TEST(FactorSolve, ForestIsTheSerialSolveOnAnyThreadCount) {
  std::vector<Scene> scenes;
  for (int k = 0; k < 12; ++k) {
    ClothGridParams cloth;
    cloth.nx = 6 + 3 * (k % 3);
    cloth.ny = 7;
    scenes.push_back(makeClothGrid(cloth));
    scenes.push_back(makeChainPendulum());
    TetBarParams bar;
    bar.nx = 2 + k % 2;
    scenes.push_back(makeTetBar(bar));
  }
  const SceneBatch batch = concatenateScenes(scenes);
  Factored f(systemOf(batch.scene, 900.0));
  const Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Random(batch.scene.numParticles(), 3);
  const std::size_t n = static_cast<std::size_t>(rhs.rows());
  for (int round = 0; round < 2; ++round) {
    ASSERT_TRUE(simplicialSolveApplies(*f.factor));
    const EliminationForest forest = findForest(*f.factor);
    ASSERT_EQ(forest.trees(), static_cast<int>(scenes.size())) << "round " << round;
    EXPECT_LT(forest.largestTreeShare(), 0.1);
    std::vector<double> work;
    Eigen::MatrixX3d serial(rhs.rows(), 3);
    solveSimplicial(*f.factor, rhs.data(), serial.data(), n, 0, 3, 4, work);
    EXPECT_LT((serial - f.cholmodSolve(rhs)).norm(), 1e-12 * serial.norm()) << "round " << round;
    const int previous = cpuThreads();
    for (int threads : {1, 2, 3}) {
      setCpuThreads(threads);
      Eigen::MatrixX3d x = Eigen::MatrixX3d::Constant(rhs.rows(), 3, -1.0);
      solveSimplicialForest(*f.factor, forest, rhs.data(), x.data(), n, work);
      int differ = 0;
      for (Eigen::Index i = 0; i < x.size(); ++i) differ += x.data()[i] != serial.data()[i];
      EXPECT_EQ(differ, 0) << threads << " threads, round " << round;
    }
    setCpuThreads(previous);
    // A pin's rank-1 update in the fifth scene (CHOLMOD then holds an LDL' factor).
    cholmod_sparse* c = cholmod_allocate_sparse(n, 1, 1, 1, 1, 0, CHOLMOD_REAL, &f.common);
    const int* perm = static_cast<const int*>(f.factor->Perm);
    const int vertex = batch.segments[4].first_particle;
    int row = 0;
    while (perm[row] != vertex) ++row;
    static_cast<int*>(c->p)[0] = 0;
    static_cast<int*>(c->p)[1] = 1;
    static_cast<int*>(c->i)[0] = row;
    static_cast<double*>(c->x)[0] = 100.0;
    ASSERT_TRUE(cholmod_updown(1, c, f.factor, &f.common));
    cholmod_free_sparse(&c, &f.common);
  }
}

// GlobalSystem::Transaction around refactorAll, which keeps each factor's analysis while c M + L
// keeps its pattern: within a Transaction the factors are computed again into copies (every
// member of a Factor copied, the pattern it was analysed for included), and the result solves
// as the refactorization in place does, bit for bit; a Transaction that does not commit puts L
// and the updated factor back, so the solves are those before it, bit for bit.
TEST(FactorSolve, ARefactorInATransactionIsTheRefactorInPlaceBitForBit) {
  ClothGridParams cloth;
  cloth.nx = cloth.ny = 20;
  const SceneData data(makeClothGrid(cloth));
  const double c = 900.0;
  const Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Random(data.numParticles(), 3);
  const auto updated = [&](GlobalSystem& system) {
    Eigen::MatrixX3d x(rhs.rows(), 3);
    system.solve(c, rhs, x);                    // factors K_c
    system.addToDiagonal({7, 30}, {1e3, 5e2});  // a rank-2 update: an LDL' factor
    system.solve(c, rhs, x);
    return x;
  };
  GlobalSystem in_place(data), in_copy(data), refused(data);
  updated(in_place);
  updated(in_copy);
  const Eigen::MatrixX3d before = updated(refused);
  const Eigen::SparseMatrix<double> l_before = refused.stiffnessLaplacian();

  in_place.refactorAll();
  {
    GlobalSystem::Transaction transaction(in_copy);
    in_copy.refactorAll();
    transaction.commit();
  }
  Eigen::MatrixX3d x_place(rhs.rows(), 3), x_copy(rhs.rows(), 3);
  in_place.solve(c, rhs, x_place);
  in_copy.solve(c, rhs, x_copy);
  for (Eigen::Index i = 0; i < x_place.size(); ++i) ASSERT_EQ(x_place.data()[i], x_copy.data()[i]) << i;
  EXPECT_EQ(in_copy.factorizations(), in_place.factorizations());

  {
    GlobalSystem::Transaction transaction(refused);
    refused.addToDiagonal(3, 2e3);
    refused.refactorAll();
  }
  Eigen::MatrixX3d x_refused(rhs.rows(), 3);
  refused.solve(c, rhs, x_refused);
  for (Eigen::Index i = 0; i < before.size(); ++i) ASSERT_EQ(before.data()[i], x_refused.data()[i]) << i;
  EXPECT_TRUE(Eigen::MatrixXd(refused.stiffnessLaplacian()) == Eigen::MatrixXd(l_before));
}

}  // namespace
}  // namespace stabint
