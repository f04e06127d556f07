// L-BFGS's history passes (history_passes.hpp).
#include "solver/history_passes.hpp"

#include "common/simd.hpp"

namespace stabint::history_passes {

// The history's passes are a few multiply-adds per value read. Eigen's dot at the library's
// baseline (two SSE2 sums) waits on its additions' latency; these kernels keep kLanes independent
// sums, compiled for AVX-512, AVX2 and the baseline (the loader picks the widest the machine has),
// each lane adding its values in index order and the lanes then summed in a fixed tree: the same
// bits on any machine (the build has no FMA contraction). The updates (q -= a y, d += c s) do
// Eigen's arithmetic, value by value. What the passes cost now is memory traffic: the vectors come
// from the last-level cache (docs/benchmarks.md, "L-BFGS's cost per iteration").

// Value i goes to lane i % kLanes, in both the whole groups and the tail.
STABINT_TARGET_CLONES
double dot(int len, const double* __restrict a, const double* __restrict b) {
  double acc[kLanes] = {};
  int i = 0;
  for (; i + kLanes <= len; i += kLanes) STABINT_LANES for (int l = 0; l < kLanes; ++l) acc[l] += a[i + l] * b[i + l];
  for (int l = 0; i + l < len; ++l) acc[l] += a[i + l] * b[i + l];
  return laneSum<kLanes>(acc);
}

// The new pair: s = x_trial - x, y = g_trial - g, then x = x_trial, g = g_trial; out = s.y, y.y,
// s.s, s.g_trial.
STABINT_TARGET_CLONES
void newPair(int len, const double* __restrict x_trial, const double* __restrict g_trial, double* __restrict x,
             double* __restrict g, double* __restrict s, double* __restrict y, double* out) {
  double sy[kLanes] = {}, yy[kLanes] = {}, ss[kLanes] = {}, sg[kLanes] = {};
  auto body = [&](int i, int l) {
    const double si = x_trial[i] - x[i], yi = g_trial[i] - g[i];
    s[i] = si;
    y[i] = yi;
    x[i] = x_trial[i];
    g[i] = g_trial[i];
    sy[l] += si * yi;
    yy[l] += yi * yi;
    ss[l] += si * si;
    sg[l] += si * g_trial[i];
  };
  int i = 0;
  for (; i + kLanes <= len; i += kLanes) STABINT_LANES for (int l = 0; l < kLanes; ++l) body(i + l, l);
  for (int l = 0; i + l < len; ++l) body(i + l, l);
  out[0] = laneSum<kLanes>(sy);
  out[1] = laneSum<kLanes>(yy);
  out[2] = laneSum<kLanes>(ss);
  out[3] = laneSum<kLanes>(sg);
}

// An older pair j against the new one: out = s.y_j, s_j.y, s_j.g_trial.
STABINT_TARGET_CLONES
void pairProducts(int len, const double* __restrict s, const double* __restrict y, const double* __restrict g_trial,
                  const double* __restrict s_j, const double* __restrict y_j, double* out) {
  double a[kLanes] = {}, b[kLanes] = {}, c[kLanes] = {};
  int i = 0;
  for (; i + kLanes <= len; i += kLanes) STABINT_LANES for (int l = 0; l < kLanes; ++l) {
      a[l] += s[i + l] * y_j[i + l];
      b[l] += s_j[i + l] * y[i + l];
      c[l] += s_j[i + l] * g_trial[i + l];
    }
  for (int l = 0; i + l < len; ++l) {
    a[l] += s[i + l] * y_j[i + l];
    b[l] += s_j[i + l] * y[i + l];
    c[l] += s_j[i + l] * g_trial[i + l];
  }
  out[0] = laneSum<kLanes>(a);
  out[1] = laneSum<kLanes>(b);
  out[2] = laneSum<kLanes>(c);
}

// q -= a v (Eigen's q - a * v, value by value).
STABINT_TARGET_CLONES
void subtractScaled(int len, double* __restrict q, double a, const double* __restrict v) {
  STABINT_LANES for (int i = 0; i < len; ++i) q[i] = q[i] - a * v[i];
}

// d += a v.
STABINT_TARGET_CLONES
void addScaled(int len, double* __restrict d, double a, const double* __restrict v) {
  STABINT_LANES for (int i = 0; i < len; ++i) d[i] = d[i] + a * v[i];
}

// d = -d; returns g.d.
STABINT_TARGET_CLONES
double negateAndSlope(int len, double* __restrict d, const double* __restrict g) {
  double acc[kLanes] = {};
  int i = 0;
  for (; i + kLanes <= len; i += kLanes) STABINT_LANES for (int l = 0; l < kLanes; ++l) {
      d[i + l] = -d[i + l];
      acc[l] += g[i + l] * d[i + l];
    }
  for (int l = 0; i + l < len; ++l) {
    d[i + l] = -d[i + l];
    acc[l] += g[i + l] * d[i + l];
  }
  return laneSum<kLanes>(acc);
}

}  // namespace stabint::history_passes
