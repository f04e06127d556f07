// The global solve alone, K_c x = rhs with K_c = c M + L for the three columns x, y, z, in the
// ways CHOLMOD (and a hand-written triangular solve over CHOLMOD's factor) can do it. The library
// uses one of them in host/solver/global_system.cpp; these cases are how it was chosen.
//   global_solve/<scene>/library            GlobalSystem::solve as the library does it
//   global_solve/<scene>/eigen-simplicial-llt   Eigen::CholmodSimplicialLLT::solve
//   global_solve/<scene>/eigen-simplicial-ldlt  Eigen::CholmodSimplicialLDLT::solve
//   global_solve/<scene>/eigen-supernodal-llt   Eigen::CholmodSupernodalLLT::solve
//   global_solve/<scene>/cholmod-solve2-llt     cholmod_solve2 with reused workspace (LL')
//   global_solve/<scene>/cholmod-solve2-ldlt    the same on the simplicial LDL' factor
//   global_solve/<scene>/interleaved-llt        L L^T solve over the packed simplicial factor,
//                                               x, y, z interleaved (one pass over L for all three)
#include "bench_common.hpp"

#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"

#include <Eigen/CholmodSupport>

#include <cholmod.h>

#include <exception>

namespace stabint::bench {
namespace {

constexpr double kC = 900.0;  // 1/h^2 at h = 1/30

Eigen::SparseMatrix<double> systemMatrix(const SceneData& data) {
  const GlobalSystem system(data);
  Eigen::SparseMatrix<double> k = system.stiffnessLaplacian();
  for (Eigen::Index j = 0; j < data.masses().size(); ++j) k.coeffRef(j, j) += kC * data.masses()[j];
  k.makeCompressed();
  return k;
}

Eigen::MatrixX3d rightHandSide(const SceneData& data) {
  Eigen::MatrixX3d rhs = data.scene().positions;
  for (Eigen::Index j = 0; j < rhs.rows(); ++j) rhs.row(j) *= kC * data.masses()[j];
  return rhs;
}

/// Raw CHOLMOD: analyse + factor once; solve with cholmod_solve2 into reused X/Y/E workspaces.
class RawCholmod {
 public:
  RawCholmod(const Eigen::SparseMatrix<double>& k, bool ll) {
    cholmod_start(&common_);
    common_.supernodal = CHOLMOD_SIMPLICIAL;
    common_.final_ll = ll ? 1 : 0;
    cholmod_sparse a =
        Eigen::viewAsCholmod(Eigen::Ref<Eigen::SparseMatrix<double>>(const_cast<Eigen::SparseMatrix<double>&>(k)));
    a.stype = -1;  // lower triangle stored (the matrix is full; CHOLMOD reads the lower half)
    factor_ = cholmod_analyze(&a, &common_);
    cholmod_factorize(&a, factor_, &common_);
    if (common_.status != CHOLMOD_OK) throw Error("CHOLMOD factorization failed");
  }
  ~RawCholmod() {
    cholmod_free_dense(&x_, &common_);
    cholmod_free_dense(&y_, &common_);
    cholmod_free_dense(&e_, &common_);
    cholmod_free_factor(&factor_, &common_);
    cholmod_finish(&common_);
  }
  RawCholmod(const RawCholmod&) = delete;
  RawCholmod& operator=(const RawCholmod&) = delete;

  void solve(const Eigen::MatrixX3d& rhs, Eigen::MatrixX3d& x) {
    cholmod_dense b{};
    b.nrow = rhs.rows();
    b.ncol = 3;
    b.nzmax = b.nrow * 3;
    b.d = b.nrow;
    b.x = const_cast<double*>(rhs.data());
    b.xtype = CHOLMOD_REAL;
    b.dtype = CHOLMOD_DOUBLE;
    cholmod_solve2(CHOLMOD_A, factor_, &b, nullptr, &x_, nullptr, &y_, &e_, &common_);
    x = Eigen::Map<const Eigen::MatrixX3d>(static_cast<const double*>(x_->x), rhs.rows(), 3);
  }
  cholmod_factor* factor() { return factor_; }
  cholmod_common& common() { return common_; }

 private:
  cholmod_common common_;
  cholmod_factor* factor_ = nullptr;
  cholmod_dense *x_ = nullptr, *y_ = nullptr, *e_ = nullptr;
};

/// P^T L L^T P x = b with CHOLMOD's packed simplicial LL' factor, the three right-hand sides
/// interleaved so that each pass over L serves x, y and z (CHOLMOD's own simplicial solve makes
/// the permutation copies and its passes column by column of the dense block).
class InterleavedLLT {
 public:
  explicit InterleavedLLT(const Eigen::SparseMatrix<double>& k) : raw_(k, true) {
    cholmod_factor* f = cholmod_copy_factor(raw_.factor(), &raw_.common());
    cholmod_change_factor(CHOLMOD_REAL, /*to_ll=*/1, /*to_super=*/0, /*to_packed=*/1, /*to_monotonic=*/1, f,
                          &raw_.common());
    n_ = static_cast<int>(f->n);
    const int* p = static_cast<const int*>(f->p);
    const int* i = static_cast<const int*>(f->i);
    const double* x = static_cast<const double*>(f->x);
    const int* perm = static_cast<const int*>(f->Perm);
    col_.assign(p, p + n_ + 1);
    row_.assign(i, i + p[n_]);
    val_.assign(x, x + p[n_]);
    perm_.assign(perm, perm + n_);
    work_.resize(3 * std::size_t(n_));
    cholmod_free_factor(&f, &raw_.common());
  }
  void solve(const Eigen::MatrixX3d& rhs, Eigen::MatrixX3d& out) {
    double* w = work_.data();
    for (int j = 0; j < n_; ++j)
      for (int d = 0; d < 3; ++d) w[3 * j + d] = rhs(perm_[j], d);
    for (int j = 0; j < n_; ++j) {  // L y = P b, column j: diagonal first
      const double inv = 1.0 / val_[col_[j]];
      const double y0 = w[3 * j] *= inv, y1 = w[3 * j + 1] *= inv, y2 = w[3 * j + 2] *= inv;
      for (int q = col_[j] + 1; q < col_[j + 1]; ++q) {
        double* r = w + 3 * row_[q];
        const double l = val_[q];
        r[0] -= l * y0;
        r[1] -= l * y1;
        r[2] -= l * y2;
      }
    }
    for (int j = n_ - 1; j >= 0; --j) {  // L^T z = y
      double s0 = w[3 * j], s1 = w[3 * j + 1], s2 = w[3 * j + 2];
      for (int q = col_[j] + 1; q < col_[j + 1]; ++q) {
        const double* r = w + 3 * row_[q];
        const double l = val_[q];
        s0 -= l * r[0];
        s1 -= l * r[1];
        s2 -= l * r[2];
      }
      const double inv = 1.0 / val_[col_[j]];
      w[3 * j] = s0 * inv;
      w[3 * j + 1] = s1 * inv;
      w[3 * j + 2] = s2 * inv;
    }
    out.resize(n_, 3);
    for (int j = 0; j < n_; ++j)
      for (int d = 0; d < 3; ++d) out(perm_[j], d) = w[3 * j + d];
  }
  long factorNonzeros() const { return static_cast<long>(val_.size()); }

 private:
  RawCholmod raw_;
  int n_ = 0;
  std::vector<int> col_, row_, perm_;
  std::vector<double> val_, work_;
};

struct SolverFixture {
  explicit SolverFixture(const Scene& s) : scene(s), data(s), k(systemMatrix(data)), rhs(rightHandSide(data)) {}
  Scene scene;
  SceneData data;
  Eigen::SparseMatrix<double> k;
  Eigen::MatrixX3d rhs;
};

template <class Solve>
void runSolve(benchmark::State& state, SolverFixture& f, Solve&& solve) {
  Eigen::MatrixX3d x(f.rhs.rows(), 3);
  solve(f.rhs, x);
  // Every variant solves the same system: report its residual so a wrong one stands out.
  const double residual = (f.k * x - f.rhs).norm() / f.rhs.norm();
  for (auto _ : state) {
    solve(f.rhs, x);
    benchmark::DoNotOptimize(x.data());
  }
  setSizeCounters(state, f.scene);
  state.counters["residual"] = residual;
}

template <class Factor>
void runEigen(benchmark::State& state, SolverFixture& f) {
  Factor factor;
  factor.compute(f.k);
  if (factor.info() != Eigen::Success) {
    state.SkipWithError("factorization failed");
    return;
  }
  runSolve(state, f, [&](const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x) { x = factor.solve(b); });
}

void runVariant(benchmark::State& state, const SceneCase& scene, const std::string& variant) {
  SolverFixture* fixture = nullptr;
  try {
    fixture = &cachedFixture<SolverFixture>("solver/" + scene.name,
                                            [&] { return std::make_unique<SolverFixture>(scene.make()); });
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  SolverFixture& f = *fixture;
  using Lower = Eigen::SparseMatrix<double>;
  if (variant == "library") {
    GlobalSystem system(f.data);
    runSolve(state, f, [&](const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x) { system.solve(kC, b, x); });
  } else if (variant == "eigen-simplicial-llt") {
    runEigen<Eigen::CholmodSimplicialLLT<Lower, Eigen::Lower>>(state, f);
  } else if (variant == "eigen-simplicial-ldlt") {
    runEigen<Eigen::CholmodSimplicialLDLT<Lower, Eigen::Lower>>(state, f);
  } else if (variant == "eigen-supernodal-llt") {
    runEigen<Eigen::CholmodSupernodalLLT<Lower, Eigen::Lower>>(state, f);
  } else if (variant == "cholmod-solve2-llt" || variant == "cholmod-solve2-ldlt") {
    RawCholmod raw(f.k, variant == "cholmod-solve2-llt");
    runSolve(state, f, [&](const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x) { raw.solve(b, x); });
  } else if (variant == "interleaved-llt") {
    InterleavedLLT solver(f.k);
    state.counters["factor_nonzeros"] = static_cast<double>(solver.factorNonzeros());
    runSolve(state, f, [&](const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x) { solver.solve(b, x); });
    state.counters["factor_nonzeros"] = static_cast<double>(solver.factorNonzeros());
  }
}

}  // namespace

void registerSolverCases() {
  std::vector<SceneCase> scenes = referenceScenes();
  scenes.push_back({"cloth224x224", [] { return clothScene(224); }});
  for (const SceneCase& scene : scenes)
    for (const char* variant : {"library", "eigen-simplicial-llt", "eigen-simplicial-ldlt", "eigen-supernodal-llt",
                                "cholmod-solve2-llt", "cholmod-solve2-ldlt", "interleaved-llt"}) {
      const std::string name = "global_solve/" + scene.name + "/" + variant;
      benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& state) { runVariant(state, scene, variant); })
          ->UseRealTime()
          ->Unit(benchmark::kMicrosecond);
    }
}

}  // namespace stabint::bench
