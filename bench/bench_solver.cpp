// The global solve alone, K_c x = rhs with K_c = c M + L for the three columns x, y, z, on the
// prefactored system, in the ways it can be done, each against its memory bound. The library uses
// one of them in host/solver/global_system.cpp; these cases are how it was chosen
// (docs/benchmarks.md, "Global solve against its bound").
//   global_solve/<scene>/library              GlobalSystem::solve as the library does it (one pass
//                                             on the calling thread, whatever cpuThreads())
//   global_solve/<scene>/cholmod-one-pass     cholmod_solve2 of the three columns at once on the
//                                             simplicial LL' factor (CHOLMOD's scalar solve, the
//                                             three columns interleaved: one pass over L)
//   global_solve/<scene>/cholmod-columns      the same, one cholmod_solve2 per column (three passes)
//   global_solve/<scene>/cholmod-groups-2t    columns {x, y} and {z} as two cholmod_solve2 on two
//                                             threads (the library before)
//   global_solve/<scene>/cholmod-supernodal   cholmod_solve2 of the three columns on the
//                                             supernodal factor (BLAS: whichever libblas.so.3 is)
//   global_solve/<scene>/vector-one-pass      solveSimplicial (host/solver/factor_solve.hpp) over
//                                             the simplicial factor, lanes {x, y, z, 0}, one thread
//   global_solve/<scene>/vector-groups-2t     the same as lanes {x, y} and {z, 0} on two threads
//   global_solve/<scene>/vector-subtrees-2t   solveSimplicialSubtrees: the backward pass over two
//                                             subtrees of the elimination tree on two threads
// Counters: factor_bytes, what one pass over the factor reads (simplicial: 8 bytes of value and 4
// of row index per entry, the column pointers and lengths; supernodal: its dense blocks, row
// indices and supernode pointers); bandwidth, bytes per second of a streaming sum over a buffer
// of factor_bytes on one thread, measured in the same case after the solves (a factor that fits
// a cache gets that cache's bandwidth; bench/scaling_chart.py takes the fastest measurement among
// a scene's cases with the same factor); bound = 2 factor_bytes / bandwidth, the seconds to read
// the factor twice (forward and backward substitution; all three columns in those two passes).
// A per-column solve reads the factor three times as often (passes counts the reads).
#include "bench_common.hpp"

#include "common/worker_pool.hpp"
#include "scene/scene_data.hpp"
#include "solver/factor_solve.hpp"
#include "solver/global_system.hpp"

#include <cholmod.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <exception>
#include <limits>

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

/// A cholmod_common and cholmod_solve2's X, Y, E buffers, one per concurrent solve.
struct Workspace {
  Workspace() {
    cholmod_start(&common);
    common.print = 0;
  }
  ~Workspace() {
    cholmod_free_dense(&x, &common);
    cholmod_free_dense(&y, &common);
    cholmod_free_dense(&e, &common);
    cholmod_finish(&common);
  }
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;
  // Columns [first, first + columns) of rhs into the same columns of out.
  void solve(cholmod_factor* factor, const Eigen::MatrixX3d& rhs, Eigen::MatrixX3d& out, int first, int columns) {
    const Eigen::Index n = rhs.rows();
    cholmod_dense b{};
    b.nrow = static_cast<std::size_t>(n);
    b.ncol = static_cast<std::size_t>(columns);
    b.nzmax = b.nrow * b.ncol;
    b.d = b.nrow;
    b.x = const_cast<double*>(rhs.data() + n * first);
    b.xtype = CHOLMOD_REAL;
    b.dtype = CHOLMOD_DOUBLE;
    cholmod_solve2(CHOLMOD_A, factor, &b, nullptr, &x, nullptr, &y, &e, &common);
    out.middleCols(first, columns) = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(x->x), n, columns);
  }
  cholmod_common common;
  cholmod_dense *x = nullptr, *y = nullptr, *e = nullptr;
};

/// The system factored once, simplicial LL' or supernodal, with CHOLMOD's default ordering (as
/// Eigen's CholmodSimplicialLLT, which the library uses).
class RawFactor {
 public:
  RawFactor(const Eigen::SparseMatrix<double>& k, bool supernodal) {
    common_.common.supernodal = supernodal ? CHOLMOD_SUPERNODAL : CHOLMOD_SIMPLICIAL;
    common_.common.final_ll = 1;
    cholmod_sparse a =
        Eigen::viewAsCholmod(Eigen::Ref<Eigen::SparseMatrix<double>>(const_cast<Eigen::SparseMatrix<double>&>(k)));
    a.stype = -1;  // lower triangle stored (the matrix is full; CHOLMOD reads the lower half)
    factor_ = cholmod_analyze(&a, &common_.common);
    if (factor_ == nullptr || !cholmod_factorize(&a, factor_, &common_.common) || common_.common.status != CHOLMOD_OK)
      throw Error("CHOLMOD factorization failed");
  }
  ~RawFactor() { cholmod_free_factor(&factor_, &common_.common); }
  RawFactor(const RawFactor&) = delete;
  RawFactor& operator=(const RawFactor&) = delete;
  cholmod_factor* factor() { return factor_; }
  double entries() const {
    if (factor_->is_super) return static_cast<double>(factor_->xsize);
    const int* nz = static_cast<const int*>(factor_->nz);
    double sum = 0.0;
    for (std::size_t j = 0; j < factor_->n; ++j) sum += nz[j];
    return sum;
  }
  // What one pass over the factor reads.
  double bytes() const {
    const double n = static_cast<double>(factor_->n);
    if (factor_->is_super) {
      return 8.0 * static_cast<double>(factor_->xsize) + 4.0 * static_cast<double>(factor_->ssize) +
             3.0 * 4.0 * static_cast<double>(factor_->nsuper + 1);
    }
    return 12.0 * entries() + 4.0 * (n + 1) + 4.0 * n;
  }

 private:
  Workspace common_;
  cholmod_factor* factor_ = nullptr;
};

// Sum of a buffer as unsigned integers: exact in any order, so the compiler vectorises it freely
// (a double sum would keep one dependent chain of additions). Built for AVX2 where the CPU has
// it, so that the reference reads at the core's full load width.
inline __attribute__((always_inline)) std::uint64_t sumWords(const std::uint64_t* p, std::size_t n) {
  std::uint64_t s = 0;
  for (std::size_t i = 0; i < n; ++i) s += p[i];
  return s;
}
std::uint64_t sumDefault(const std::uint64_t* p, std::size_t n) { return sumWords(p, n); }
#if defined(__x86_64__)
__attribute__((target("avx2"))) std::uint64_t sumAvx2(const std::uint64_t* p, std::size_t n) { return sumWords(p, n); }
#endif

/// Seconds to read `bytes` once on this thread, streaming: the fastest of repeated sums over one
/// buffer of that size (warm: where it fits a cache, it is read from there, as the factor is).
double streamSeconds(double bytes) {
  static std::vector<std::uint64_t> buffer;
  const std::size_t words = std::max<std::size_t>(8, static_cast<std::size_t>(bytes / 8.0));
  buffer.assign(words, 1);
  std::uint64_t (*sum)(const std::uint64_t*, std::size_t) = sumDefault;
#if defined(__x86_64__)
  if (__builtin_cpu_supports("avx2")) sum = sumAvx2;
#endif
  using Clock = std::chrono::steady_clock;
  double best = std::numeric_limits<double>::infinity(), spent = 0.0;
  benchmark::DoNotOptimize(sum(buffer.data(), words));
  for (int r = 0; r < 100000 && (r < 20 || spent < 0.05); ++r) {
    const auto start = Clock::now();
    benchmark::DoNotOptimize(sum(buffer.data(), words));
    const double t = std::chrono::duration<double>(Clock::now() - start).count();
    best = std::min(best, t);
    spent += t;
  }
  buffer.clear();
  buffer.shrink_to_fit();
  return best;
}

struct SolverFixture {
  explicit SolverFixture(const Scene& s) : scene(s), data(s), k(systemMatrix(data)), rhs(rightHandSide(data)) {}
  RawFactor& simplicial() {
    if (!simplicial_) simplicial_ = std::make_unique<RawFactor>(k, false);
    return *simplicial_;
  }
  RawFactor& supernodal() {
    if (!supernodal_) supernodal_ = std::make_unique<RawFactor>(k, true);
    return *supernodal_;
  }
  Scene scene;
  SceneData data;
  Eigen::SparseMatrix<double> k;
  Eigen::MatrixX3d rhs;

 private:
  std::unique_ptr<RawFactor> simplicial_, supernodal_;
};

template <class Solve>
void runSolve(benchmark::State& state, SolverFixture& f, RawFactor& factor, double passes, Solve&& solve) {
  Eigen::MatrixX3d x(f.rhs.rows(), 3);
  solve(f.rhs, x);
  // Every variant solves the same system: report its residual so a wrong one stands out.
  const double residual = (f.k * x - f.rhs).norm() / f.rhs.norm();
  for (auto _ : state) {
    solve(f.rhs, x);
    benchmark::DoNotOptimize(x.data());
  }
  const double bytes = factor.bytes();
  const double stream = streamSeconds(bytes);
  setSizeCounters(state, f.scene);
  state.counters["residual"] = residual;
  state.counters["factor_entries"] = factor.entries();
  state.counters["factor_bytes"] = bytes;
  state.counters["bandwidth"] = bytes / stream;
  state.counters["bound"] = 2.0 * stream;
  state.counters["passes"] = passes;
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
  const std::size_t n = static_cast<std::size_t>(f.rhs.rows());
  if (variant == "library") {
    GlobalSystem system(f.data);
    runSolve(state, f, f.simplicial(), 2,
             [&](const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x) { system.solve(kC, b, x); });
  } else if (variant == "cholmod-one-pass" || variant == "cholmod-columns") {
    Workspace w;
    const bool columns = variant == "cholmod-columns";
    runSolve(state, f, f.simplicial(), columns ? 6 : 2, [&](const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x) {
      if (columns) {
        for (int c = 0; c < 3; ++c) w.solve(f.simplicial().factor(), b, x, c, 1);
      } else {
        w.solve(f.simplicial().factor(), b, x, 0, 3);
      }
    });
  } else if (variant == "cholmod-groups-2t") {
    ThreadsFor two(2);
    Workspace w[2];
    runSolve(state, f, f.simplicial(), 2, [&](const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x) {
      parallelFor(2, [&](int g) { w[g].solve(f.simplicial().factor(), b, x, g == 0 ? 0 : 2, g == 0 ? 2 : 1); });
    });
  } else if (variant == "cholmod-supernodal") {
    Workspace w;
    runSolve(state, f, f.supernodal(), 2,
             [&](const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x) { w.solve(f.supernodal().factor(), b, x, 0, 3); });
  } else if (variant == "vector-one-pass") {
    std::vector<double> work;
    runSolve(state, f, f.simplicial(), 2, [&](const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x) {
      solveSimplicial(*f.simplicial().factor(), b.data(), x.data(), n, 0, 3, 4, work);
    });
  } else if (variant == "vector-subtrees-2t") {
    ThreadsFor two(2);
    std::vector<double> work;
    const SubtreeSplit split = findSubtreeSplit(*f.simplicial().factor());
    runSolve(state, f, f.simplicial(), 2, [&](const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x) {
      solveSimplicialSubtrees(*f.simplicial().factor(), split, b.data(), x.data(), n, work);
    });
    const double total = static_cast<double>(f.simplicial().entries());
    const int* nz = static_cast<const int*>(f.simplicial().factor()->nz);
    double a = 0, b = 0;
    for (int j = 0; j < split.b_end; ++j) (j < split.a_end ? a : b) += nz[j];
    state.counters["subtree_a"] = a / total;  // shares of the factor's entries in the two subtrees
    state.counters["subtree_b"] = b / total;
  } else if (variant == "vector-groups-2t") {
    ThreadsFor two(2);
    std::vector<double> work[2];
    runSolve(state, f, f.simplicial(), 2, [&](const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x) {
      parallelFor(2, [&](int g) {
        solveSimplicial(*f.simplicial().factor(), b.data(), x.data(), n, g == 0 ? 0 : 2, g == 0 ? 2 : 1, 2, work[g]);
      });
    });
  }
}

}  // namespace

void registerSolverCases() {
  // The cloth scaling family (with the 200 x 200 cloth), the reference tet bar and the tet bars of
  // autoRuleScenes() (its 49 x 9 x 9 cells bar is the reference bar).
  std::vector<SceneCase> scenes;
  std::vector<int> sides = scalingSides();
  if (!quickMode()) sides.push_back(200);
  std::sort(sides.begin(), sides.end());
  for (int side : sides) {
    const std::string size = std::to_string(side) + "x" + std::to_string(side);
    scenes.push_back({"cloth" + size, [side] { return clothScene(side); }});
  }
  for (const SceneCase& scene : autoRuleScenes())
    if (scene.name.rfind("tetbar", 0) == 0 && scene.name != "tetbar49x9x9") scenes.push_back(scene);
  for (const SceneCase& scene : referenceScenes())
    if (scene.name.rfind("tetbar", 0) == 0) scenes.push_back(scene);
  for (const SceneCase& scene : scenes)
    for (const char* variant : {"library", "cholmod-one-pass", "cholmod-columns", "cholmod-groups-2t",
                                "cholmod-supernodal", "vector-one-pass", "vector-groups-2t", "vector-subtrees-2t"}) {
      const std::string name = "global_solve/" + scene.name + "/" + variant;
      benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& state) { runVariant(state, scene, variant); })
          ->UseRealTime()
          ->Unit(benchmark::kMicrosecond);
    }
}

}  // namespace stabint::bench
