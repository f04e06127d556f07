#pragma once
// L-BFGS's passes over its history (host/solver/lbfgs.cpp): fused multiply-add kernels over
// `len` contiguous values and the loops that run them over a segment's rows in cache-sized chunks
// and over a batch's segments on threads.
#include "common/worker_pool.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace stabint::history_passes {

// The history's passes (their definitions and why they are written so: history_passes.cpp).
// Value i of a pass goes to lane i % kLanes of kLanes independent sums, the lanes then added in a
// fixed tree: the same bits on any machine.
constexpr int kLanes = 16;

/// a.b over `len` values.
double dot(int len, const double* a, const double* b);
/// The new pair: s = x_trial - x, y = g_trial - g, then x = x_trial, g = g_trial; out = s.y, y.y,
/// s.s, s.g_trial.
void newPair(int len, const double* x_trial, const double* g_trial, double* x, double* g, double* s, double* y,
             double* out);
/// An older pair j against the new one: out = s.y_j, s_j.y, s_j.g_trial.
void pairProducts(int len, const double* s, const double* y, const double* g_trial, const double* s_j,
                  const double* y_j, double* out);
/// q -= a v (Eigen's q - a * v, value by value).
void subtractScaled(int len, double* q, double a, const double* v);
/// d += a v.
void addScaled(int len, double* d, double a, const double* v);
/// d = -d; returns g.d.
double negateAndSlope(int len, double* d, const double* g);

// The rows of one segment in each of the three columns of an `n by 3` (column-major) matrix, in
// chunks short enough that the chunk of every vector a fused pass reads stays in cache: f(offset,
// length) per chunk, the offset into the matrix's data.
template <class F>
void forEachChunk(int first, int count, Eigen::Index n, F&& f) {
  constexpr int kChunk = 512;
  for (Eigen::Index col = 0; col < 3; ++col)
    for (int i = 0; i < count; i += kChunk) f(col * n + first + i, std::min(kChunk, count - i));
}

// A batch's history passes go on threads from this many particles: its vectors then no longer fit
// a core's caches, and a pass over them (milliseconds) dwarfs a worker's wake-up (20-30 us).
constexpr int kThreadedHistoryParticles = 10'000;

// f(seg) for every segment: on cpuThreads() threads, each a contiguous run of segments of about
// equal rows, where a batch is that large. A segment's sums are its own and add in the same order
// on any thread, so the results are the serial loop's bit for bit.
template <class Rows, class F>
void forEachSegment(const std::vector<Rows>& rows, F&& f) {
  const std::size_t segments = rows.size();
  const int threads = cpuThreads();
  const int particles = segments == 0 ? 0 : rows.back().first + rows.back().count - rows.front().first;
  if (segments < 2 || threads < 2 || particles < kThreadedHistoryParticles) {
    for (std::size_t seg = 0; seg < segments; ++seg) f(seg);
    return;
  }
  std::vector<double> work(segments + 1, 0.0);  // by rows
  for (std::size_t seg = 0; seg < segments; ++seg) work[seg + 1] = work[seg] + rows[seg].count;
  parallelForRuns(work, f);
}

}  // namespace stabint::history_passes
