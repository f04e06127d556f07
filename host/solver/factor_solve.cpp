#include "solver/factor_solve.hpp"

#include <cstdint>

namespace stabint {
namespace {

// GCC/Clang vector extensions: arithmetic lane by lane, a V4 two SSE2 operations where AVX is
// not enabled. may_alias: a row of the work buffer (aligned to its size) is read and written in
// place as one. No function takes or returns one (that ABI would depend on the target).
typedef double V2 __attribute__((vector_size(16), may_alias));
typedef double V4 __attribute__((vector_size(32), may_alias));

#define STABINT_ROW(V, y, W, i) (*reinterpret_cast<V*>((y) + std::size_t(W) * (i)))

// L y = b (forward) and L^T x = y (backward) on the permuted rows in `y` (row-major, W lanes a
// row); LDL' has a unit L and D on the diagonal. The arithmetic per lane does not depend on W.
template <class V, bool LL>
inline __attribute__((always_inline)) void substitute(const cholmod_factor& factor, double* y) {
  constexpr int W = sizeof(V) / sizeof(double);
  const int n = static_cast<int>(factor.n);
  const int* lp = static_cast<const int*>(factor.p);
  const int* li = static_cast<const int*>(factor.i);
  const int* lnz = static_cast<const int*>(factor.nz);
  const double* lx = static_cast<const double*>(factor.x);
  // Columns j and j + 1 are a pair where column j + 1 has the rows of column j below j + 1, in
  // the same order (its first row is j + 1 and it is one entry shorter: the rows of column j
  // below the diagonal are those of its etree parent's column, so equal counts mean equal rows):
  // each row of the right-hand side they touch is then read and written once for both.
  const auto pairsWithNext = [&](int j) {
    return j + 1 < n && lnz[j] >= 2 && li[lp[j] + 1] == j + 1 && lnz[j + 1] == lnz[j] - 1;
  };
  // Forward, L y = b, column by column (CHOLMOD keeps the diagonal first in each column): y_j is
  // final once the columns before it have been subtracted; subtract L(i, j) y_j from rows below.
  for (int j = 0; j < n;) {
    const int p = lp[j], end = p + lnz[j];
    V y0 = STABINT_ROW(V, y, W, j);
    if (LL) y0 = y0 / lx[p];
    STABINT_ROW(V, y, W, j) = y0;
    if (!pairsWithNext(j)) {
      for (int q = p + 1; q < end; ++q) {
        V& row = STABINT_ROW(V, y, W, li[q]);
        row = row - lx[q] * y0;
      }
      ++j;
      continue;
    }
    const int r = lp[j + 1];
    V y1 = STABINT_ROW(V, y, W, j + 1) - lx[p + 1] * y0;
    if (LL) y1 = y1 / lx[r];
    STABINT_ROW(V, y, W, j + 1) = y1;
    for (int q = p + 2, t = r + 1; q < end; ++q, ++t) {
      V& row = STABINT_ROW(V, y, W, li[q]);
      row = row - (lx[q] * y0 + lx[t] * y1);
    }
    j += 2;
  }
  // Backward, L^T x = y (LDL': D^-1 y), column j of L as row j of L^T: x_j = (y_j - sum_i L(i, j)
  // x_i) / L(j, j). Single columns sum on four partial sums (entries q, q+1, q+2, q+3 of the
  // column to s0..s3, added as (s0 + s1) + (s2 + s3)), pairs on two each, so that four products
  // are in flight at a time.
  for (int j = n - 1; j >= 0;) {
    const int p = lp[j], end = p + lnz[j];
    V s0 = STABINT_ROW(V, y, W, j);
    if (!LL) s0 = s0 / lx[p];
    if (j >= 1 && pairsWithNext(j - 1)) {
      const int a = lp[j - 1];  // column j - 1: its diagonal, L(j, j - 1), then the rows of column j
      V t0 = STABINT_ROW(V, y, W, j - 1);
      if (!LL) t0 = t0 / lx[a];
      V s1 = {}, t1 = {};
      int q = p + 1, u = a + 2;
      for (; q + 1 < end; q += 2, u += 2) {
        const V x0 = STABINT_ROW(V, y, W, li[q]), x1 = STABINT_ROW(V, y, W, li[q + 1]);
        s0 -= lx[q] * x0;
        t0 -= lx[u] * x0;
        s1 -= lx[q + 1] * x1;
        t1 -= lx[u + 1] * x1;
      }
      if (q < end) {
        const V x0 = STABINT_ROW(V, y, W, li[q]);
        s0 -= lx[q] * x0;
        t0 -= lx[u] * x0;
      }
      V xj = s0 + s1;
      if (LL) xj = xj / lx[p];
      V xk = (t0 + t1) - lx[a + 1] * xj;
      if (LL) xk = xk / lx[a];
      STABINT_ROW(V, y, W, j) = xj;
      STABINT_ROW(V, y, W, j - 1) = xk;
      j -= 2;
      continue;
    }
    V s1 = {}, s2 = {}, s3 = {};
    int q = p + 1;
    for (; q + 3 < end; q += 4) {
      s0 -= lx[q] * STABINT_ROW(V, y, W, li[q]);
      s1 -= lx[q + 1] * STABINT_ROW(V, y, W, li[q + 1]);
      s2 -= lx[q + 2] * STABINT_ROW(V, y, W, li[q + 2]);
      s3 -= lx[q + 3] * STABINT_ROW(V, y, W, li[q + 3]);
    }
    if (q < end) s0 -= lx[q] * STABINT_ROW(V, y, W, li[q]);
    if (q + 1 < end) s1 -= lx[q + 1] * STABINT_ROW(V, y, W, li[q + 1]);
    if (q + 2 < end) s2 -= lx[q + 2] * STABINT_ROW(V, y, W, li[q + 2]);
    V xj = (s0 + s1) + (s2 + s3);
    if (LL) xj = xj / lx[p];
    STABINT_ROW(V, y, W, j) = xj;
    --j;
  }
}

template <class V>
inline __attribute__((always_inline)) void substituteAny(const cholmod_factor& factor, double* y) {
  if (factor.is_ll) {
    substitute<V, true>(factor, y);
  } else {
    substitute<V, false>(factor, y);
  }
}

void substituteDefault(const cholmod_factor& factor, double* y, int lanes) {
  if (lanes == 4) {
    substituteAny<V4>(factor, y);
  } else {
    substituteAny<V2>(factor, y);
  }
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
// The same code with 256-bit AVX operations (no FMA: a fused multiply-add would round once where
// the default build rounds twice, so the results would depend on the machine).
__attribute__((target("avx"))) void substituteAvx(const cholmod_factor& factor, double* y, int lanes) {
  if (lanes == 4) {
    substituteAny<V4>(factor, y);
  } else {
    substituteAny<V2>(factor, y);
  }
}
bool haveAvx() {
  static const bool avx = __builtin_cpu_supports("avx");
  return avx;
}
#endif

}  // namespace

bool simplicialSolveApplies(const cholmod_factor& factor) {
  return factor.is_super == 0 && factor.xtype == CHOLMOD_REAL && factor.dtype == CHOLMOD_DOUBLE &&
         factor.itype == CHOLMOD_INT && factor.p != nullptr && factor.nz != nullptr;
}

void solveSimplicial(const cholmod_factor& factor, const double* rhs, double* x, std::size_t ld, int first, int columns,
                     int lanes, std::vector<double>& buffer) {
  const std::size_t n = factor.n;
  // The rows (vectors of `lanes` doubles) at multiples of their size: from a 64-byte boundary.
  buffer.resize(std::size_t(lanes) * n + 8);
  const std::uintptr_t address = reinterpret_cast<std::uintptr_t>(buffer.data());
  double* work = buffer.data() + ((64 - address % 64) % 64) / sizeof(double);
  const int* perm = static_cast<const int*>(factor.Perm);
  // Row k of the permuted system is row perm[k] of the original; unused lanes are zero.
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t row = perm ? static_cast<std::size_t>(perm[k]) : k;
    double* w = work + std::size_t(lanes) * k;
    for (int c = 0; c < lanes; ++c) w[c] = c < columns ? rhs[row + ld * std::size_t(first + c)] : 0.0;
  }
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  if (haveAvx()) {
    substituteAvx(factor, work, lanes);
  } else {
    substituteDefault(factor, work, lanes);
  }
#else
  substituteDefault(factor, work, lanes);
#endif
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t row = perm ? static_cast<std::size_t>(perm[k]) : k;
    const double* w = work + std::size_t(lanes) * k;
    for (int c = 0; c < columns; ++c) x[row + ld * std::size_t(first + c)] = w[c];
  }
}

}  // namespace stabint
