#include "solver/factor_solve.hpp"

#include "common/worker_pool.hpp"

#include <algorithm>
#include <cstdint>
#include <vector>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace stabint {
namespace {

// GCC/Clang vector extensions: arithmetic lane by lane, a V4 two SSE2 operations where AVX is
// not enabled. may_alias: a row of the work buffer (aligned to its size) is read and written in
// place as one. No function takes or returns one (that ABI would depend on the target).
typedef double V2 __attribute__((vector_size(16), may_alias));
typedef double V4 __attribute__((vector_size(32), may_alias));

#define STABINT_ROW(V, y, W, i) (*reinterpret_cast<V*>((y) + std::size_t(W) * (i)))

// The factor's arrays (CHOLMOD's simplicial layout: column j's entries at p[j], p[j] + 1, ...,
// nz[j] of them, the diagonal first, then the rows below it in ascending order).
struct Columns {
  const int* p;
  const int* i;
  const int* nz;
  const double* x;
  int n;
  // Whether column j + 1 has the rows of column j below j + 1: its first row is j + 1 and it is
  // one entry shorter (column j's rows below the diagonal are among those of its etree parent's
  // column, so equal counts mean equal rows, in the same ascending order).
  bool chainsToNext(int j) const { return j + 1 < n && nz[j] >= 2 && i[p[j] + 1] == j + 1 && nz[j + 1] == nz[j] - 1; }
};

namespace plain {
#define STABINT_FUSED 0
#include "solver/factor_solve_kernels.inc"
#undef STABINT_FUSED
}  // namespace plain

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
// The same code for AVX2 with fused multiply-adds, used where the CPU has them (every x86-64 CPU
// since 2013-2015): half the floating-point operations per factor entry. A fused multiply-add
// rounds once where the plain code rounds twice, so the result depends on the CPU's instruction
// set (never on the thread count).
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2,fma"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2,fma")
#endif
namespace fused {
#define STABINT_FUSED 1
#include "solver/factor_solve_kernels.inc"
#undef STABINT_FUSED
}  // namespace fused
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif
#define STABINT_HAVE_FUSED 1

// The same again with AVX-512VL enabled (still 256-bit vectors): a multiply-add takes its
// broadcast factor entry straight from memory, one instruction instead of two. The same
// operations as `fused`, so the same result.
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2,fma,avx512f,avx512vl"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2,fma,avx512f,avx512vl")
#endif
namespace wide {
#define STABINT_FUSED 1
#include "solver/factor_solve_kernels.inc"
#undef STABINT_FUSED
}  // namespace wide
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif

bool haveAvx512() {
  static const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  return avx512;
}

bool haveFma() {
  static const bool fma = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return fma;
}
#endif

}  // namespace

bool simplicialSolveApplies(const cholmod_factor& factor) {
  return factor.is_super == 0 && factor.xtype == CHOLMOD_REAL && factor.dtype == CHOLMOD_DOUBLE &&
         factor.itype == CHOLMOD_INT && factor.p != nullptr && factor.nz != nullptr;
}

namespace {

// The columns [lo, hi) of the chosen build (passes: 1 forward, 2 backward, 3 both).
void substituteRange(const cholmod_factor& factor, double* work, double* inverse, int lanes, int passes, int lo,
                     int hi) {
#if defined(STABINT_HAVE_FUSED)
  if (haveFma() && haveAvx512()) {
    wide::substituteAll(factor, work, inverse, lanes, passes, lo, hi);
  } else if (haveFma()) {
    fused::substituteAll(factor, work, inverse, lanes, passes, lo, hi);
  } else {
    plain::substituteAll(factor, work, inverse, lanes, passes, lo, hi);
  }
#else
  plain::substituteAll(factor, work, inverse, lanes, passes, lo, hi);
#endif
}

// The rows (vectors of `lanes` doubles) at multiples of their size, from a 64-byte boundary of
// `buffer`, then the n reciprocal diagonal entries.
double* rowsIn(std::vector<double>& buffer, std::size_t n, int lanes) {
  buffer.resize(std::size_t(lanes + 1) * n + 8);
  const std::uintptr_t address = reinterpret_cast<std::uintptr_t>(buffer.data());
  return buffer.data() + ((64 - address % 64) % 64) / sizeof(double);
}

// Rows [lo, hi) (all by default) of the permuted system: row k is row perm[k] of the original;
// unused lanes are zero.
void permuteIn(const cholmod_factor& factor, const double* b, std::size_t ld, int columns, int lanes, double* work,
               std::size_t lo = 0, std::size_t hi = SIZE_MAX) {
  const int* perm = static_cast<const int*>(factor.Perm);
  for (std::size_t k = lo; k < std::min<std::size_t>(hi, factor.n); ++k) {
    const std::size_t row = perm ? static_cast<std::size_t>(perm[k]) : k;
    double* w = work + std::size_t(lanes) * k;
    for (int c = 0; c < lanes; ++c) w[c] = c < columns ? b[row + ld * std::size_t(c)] : 0.0;
  }
}

void permuteOut(const cholmod_factor& factor, const double* work, std::size_t ld, int columns, int lanes, double* out,
                std::size_t lo = 0, std::size_t hi = SIZE_MAX) {
  const int* perm = static_cast<const int*>(factor.Perm);
  for (std::size_t k = lo; k < std::min<std::size_t>(hi, factor.n); ++k) {
    const std::size_t row = perm ? static_cast<std::size_t>(perm[k]) : k;
    const double* w = work + std::size_t(lanes) * k;
    for (int c = 0; c < columns; ++c) out[row + ld * std::size_t(c)] = w[c];
  }
}

}  // namespace

void solveSimplicial(const cholmod_factor& factor, const double* rhs, double* x, std::size_t ld, int first, int columns,
                     int lanes, std::vector<double>& buffer) {
  const std::size_t n = factor.n;
  double* work = rowsIn(buffer, n, lanes);
  permuteIn(factor, rhs + ld * std::size_t(first), ld, columns, lanes, work);
  substituteRange(factor, work, work + std::size_t(lanes) * n, lanes, 3, 0, static_cast<int>(n));
  permuteOut(factor, work, ld, columns, lanes, x + ld * std::size_t(first));
}

namespace {

// Per column of a factor's elimination tree (the etree parent of column j is its first row below
// the diagonal): its subtree's size and smallest column, and the entries of the columns before
// it (before[n]: all of them). Empty when the factor is not postordered (every subtree the
// columns [j - size + 1, j]; CHOLMOD postorders, and cholmod_updown may change the tree).
struct TreeShape {
  std::vector<int> size;
  std::vector<double> before;
};
TreeShape treeShape(const cholmod_factor& factor) {
  const int n = static_cast<int>(factor.n);
  const int* p = static_cast<const int*>(factor.p);
  const int* i = static_cast<const int*>(factor.i);
  const int* nz = static_cast<const int*>(factor.nz);
  TreeShape t;
  t.size.assign(static_cast<std::size_t>(n), 1);
  t.before.assign(static_cast<std::size_t>(n) + 1, 0.0);
  std::vector<int> lowest(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) lowest[j] = j;
  for (int j = 0; j < n; ++j) {
    t.before[j + 1] = t.before[j] + nz[j];
    if (nz[j] > 1) {
      const int parent = i[p[j] + 1];
      t.size[parent] += t.size[j];
      lowest[parent] = std::min(lowest[parent], lowest[j]);
    }
  }
  for (int j = 0; j < n; ++j)
    if (lowest[j] != j - t.size[j] + 1) return {};
  return t;
}

}  // namespace

SubtreeSplit findSubtreeSplit(const cholmod_factor& factor) {
  const int n = static_cast<int>(factor.n);
  const TreeShape t = treeShape(factor);
  if (t.size.empty()) return {0, 0};
  SubtreeSplit best{0, 0};
  double cost = t.before[n];  // the backward pass on one thread
  for (int c = 0; c < n; ++c) {
    const int start = c - t.size[c] + 1;
    const double a = t.before[start], b = t.before[c + 1] - t.before[start], top = t.before[n] - t.before[c + 1];
    if (std::max(a, b) + top < cost) {
      cost = std::max(a, b) + top;
      best = {start, c + 1};
    }
  }
  return best;
}

double EliminationForest::largestTreeShare() const {
  double largest = 0.0;
  for (std::size_t t = 0; t + 1 < entries.size(); ++t) largest = std::max(largest, entries[t + 1] - entries[t]);
  return entries.empty() || entries.back() <= 0.0 ? 1.0 : largest / entries.back();
}

EliminationForest findForest(const cholmod_factor& factor) {
  const int n = static_cast<int>(factor.n);
  const int* nz = static_cast<const int*>(factor.nz);
  const TreeShape t = treeShape(factor);
  EliminationForest forest;
  if (t.size.empty()) return forest;
  // A root (no entry below its diagonal) ends its tree, which starts size - 1 columns before it.
  for (int j = 0; j < n; ++j) {
    if (nz[j] > 1) continue;
    forest.starts.push_back(j - t.size[j] + 1);
    forest.entries.push_back(t.before[j - t.size[j] + 1]);
  }
  forest.starts.push_back(n);
  forest.entries.push_back(t.before[n]);
  return forest;
}

void solveSimplicialSubtrees(const cholmod_factor& factor, const SubtreeSplit& split, const double* rhs, double* x,
                             std::size_t ld, std::vector<double>& buffer) {
  const std::size_t n = factor.n;
  double* work = rowsIn(buffer, n, 4);
  double* inverse = work + 4 * n;
  permuteIn(factor, rhs, ld, 3, 4, work);
  substituteRange(factor, work, inverse, 4, 1, 0, static_cast<int>(n));
  substituteRange(factor, work, inverse, 4, 2, split.b_end, static_cast<int>(n));
  parallelFor(2, [&](int part) {
    substituteRange(factor, work, inverse, 4, 2, part == 0 ? 0 : split.a_end, part == 0 ? split.a_end : split.b_end);
  });
  permuteOut(factor, work, ld, 3, 4, x);
}

void solveSimplicialForest(const cholmod_factor& factor, const EliminationForest& forest, const double* rhs, double* x,
                           std::size_t ld, std::vector<double>& buffer, const std::vector<char>* solved,
                           bool threaded) {
  const std::size_t n = factor.n;
  double* work = rowsIn(buffer, n, 4);
  double* inverse = work + 4 * n;
  auto solveTree = [&](std::size_t tree) {
    if (solved && !(*solved)[tree]) return;
    const std::size_t lo = std::size_t(forest.starts[tree]), hi = std::size_t(forest.starts[tree + 1]);
    permuteIn(factor, rhs, ld, 3, 4, work, lo, hi);
    substituteRange(factor, work, inverse, 4, 3, int(lo), int(hi));
    permuteOut(factor, work, ld, 3, 4, x, lo, hi);
  };
  if (!threaded) {
    for (int tree = 0; tree < forest.trees(); ++tree) solveTree(std::size_t(tree));
    return;
  }
  if (!solved) {
    parallelForRuns(forest.entries, solveTree);
    return;
  }
  // The runs split the work of the trees solved (per thread, kept: no allocation per solve).
  thread_local std::vector<double> work_before;
  work_before.assign(forest.entries.size(), 0.0);
  for (int tree = 0; tree < forest.trees(); ++tree) {
    const std::size_t t = std::size_t(tree);
    work_before[t + 1] = work_before[t] + ((*solved)[t] ? forest.entries[t + 1] - forest.entries[t] : 0.0);
  }
  parallelForRuns(work_before, solveTree);
}

}  // namespace stabint
