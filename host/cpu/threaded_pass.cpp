// Which element passes of the CPU reference go on threads, and how: the cost model and the
// splits of the Owned path (docs/method.md section 12; the passes themselves are CpuBackend's).
#include "cpu/threaded_pass.hpp"

#include "scene/scene_data.hpp"

#include <algorithm>
#include <cmath>

namespace stabint {
namespace threaded_pass {
namespace {

// The cost model, in nanoseconds, measured on the 2-core development VM (bench/bench_thread_pass.cpp;
// docs/benchmarks.md, "Threads in the element passes"). On one thread a kind's element costs its
// ElementType::elementCost (Kind::kElementNs), less kScatterNs per contribution in a pass that
// writes none (an energy pass). On threads:
//   kDispatchNs  what a parallelFor costs the calling thread before its first task (waking the
//                workers: a system call)
//   kWakeNs      how much later than the calling thread a sleeping worker starts its first task
//                (thread_pass_wake measures the two together: 33-45 us on the Intel Xeon host
//                of the VM, 4.3 us on the AMD EPYC one; the constants sit between the two, and
//                a threaded pass gives the serial pass's results bit for bit either way)
//   kSharedNs    what each element costs more on one of two threads working at once than alone
//                (the memory traffic the cores share): fitted to the spring cloths' passes
//   kSumNs       one stored energy added to its block's sum on the calling thread afterwards
//                (sumEnergies: chunks side by side, at the additions' throughput)
//   kBufferNs, kGatherNs  a contribution's extra write to the buffer and its read in the gather
// A pass goes on threads only when its estimated time there is at most kThreadedGain of its
// estimated time on one thread: a margin for the estimates, and for a second core that the
// machine's other work takes now and then.
constexpr double kScatterNs = 1.3;
constexpr double kDispatchNs = 5'000.0;
constexpr double kWakeNs = 10'000.0;
constexpr double kSharedNs = 1.2;
constexpr double kSumNs = 0.2;
constexpr double kBufferNs = 1.0;
constexpr double kGatherNs = 1.5;
constexpr double kThreadedGain = 0.85;

// An element's estimated cost in a pass with `flags` on one thread: its kind's local-step cost,
// less kScatterNs per contribution in a pass that writes none.
double elementNs(const ElementType& type, int flags) {
  const double cost = std::max(type.elementCost(), 1.0);
  if (flags & (kPassProjection | kPassForce)) return cost;
  return std::max(cost - kScatterNs * type.shape().vertices, 0.25 * cost);
}
// The same on one of several threads at once.
double threadedNs(const ElementType& type, int flags) { return elementNs(type, flags) + kSharedNs; }

}  // namespace

std::size_t threadedBlocks(const std::vector<ElementBlock>& blocks, int flags) {
  static const Eigen::MatrixX3d none;
  std::size_t count = 0;
  for (; count < blocks.size(); ++count) {
    const ElementBlock& b = blocks[count];
    if (!b.type->elementResults(b, b.params, none, 0, 0, flags, nullptr, nullptr) ||
        !b.type->ownedResults(b, b.params, none, 0, 0, flags, 0, 0, nullptr, nullptr))
      break;
  }
  return count;
}

PassWork passWork(const std::vector<ElementBlock>& blocks, std::size_t count, int flags) {
  const bool write = (flags & (kPassProjection | kPassForce)) != 0;
  PassWork w;
  for (std::size_t b = 0; b < count; ++b) {
    w.elements += blocks[b].count * elementNs(*blocks[b].type, flags);
    if (write) w.contributions += double(blocks[b].count) * blocks[b].type->shape().vertices;
    w.count += blocks[b].count;
  }
  return w;
}

bool mayPay(const PassWork& w, int threads) {
  return (w.elements + kSharedNs * w.count) / threads + kDispatchNs <= kThreadedGain * w.elements;
}

OwnedPlan makeOwnedPlan(const SceneData& scene, std::size_t count, int parts) {
  const std::vector<ElementBlock>& blocks = scene.blocks();
  OwnedPlan plan;
  plan.key = {parts};
  for (std::size_t b = 0; b < count; ++b) plan.key.insert(plan.key.end(), {blocks[b].count, blocks[b].revision});
  const int n = scene.numParticles();
  std::vector<double> work(static_cast<std::size_t>(n), 0.0);
  double total = 0.0;
  for (std::size_t b = 0; b < count; ++b) {
    const int k = blocks[b].type->shape().vertices;
    const double cost = threadedNs(*blocks[b].type, kPassProjection);
    for (int v : blocks[b].vertices) work[size_t(v)] += cost / k;
    total += cost * blocks[b].count;
  }
  // Part 0 takes the others' share plus kWakeNs; equal shares for a pass too small for that
  // (only a forced path runs such a pass on threads).
  double first = (total + (parts - 1) * kWakeNs) / parts;
  if (first >= total) first = total / parts;
  const double other = parts > 1 ? (total - first) / (parts - 1) : 0.0;
  plan.bounds.assign(std::size_t(parts) + 1, n);
  plan.bounds[0] = 0;
  double sum = 0.0;
  int part = 1;
  for (int v = 0; v < n && part < parts; ++v) {
    sum += work[size_t(v)];
    while (part < parts && sum >= first + (part - 1) * other) plan.bounds[size_t(part++)] = v + 1;
  }
  plan.runs.resize(std::size_t(parts));
  plan.work.assign(std::size_t(parts), 0.0);
  for (int p = 0; p < parts; ++p) {
    const int lo = plan.bounds[size_t(p)], hi = plan.bounds[size_t(p) + 1];
    std::vector<Run>& runs = plan.runs[size_t(p)];
    for (std::size_t b = 0; b < count; ++b) {
      const int k = blocks[b].type->shape().vertices;
      const double cost = threadedNs(*blocks[b].type, kPassProjection);
      const int* vertices = blocks[b].vertices.data();
      for (int e = 0; e < blocks[b].count; ++e) {
        bool touches = false;
        for (int j = 0; j < k; ++j) touches = touches || (vertices[k * e + j] >= lo && vertices[k * e + j] < hi);
        if (!touches) continue;
        plan.work[size_t(p)] += cost;
        if (!runs.empty() && runs.back().block == b && runs.back().first + runs.back().count == e) {
          ++runs.back().count;
        } else {
          runs.push_back({b, e, 1});
        }
      }
    }
  }
  return plan;
}

EnergySplit splitEnergyPass(const std::vector<ElementBlock>& blocks, std::size_t count, int parts, int flags) {
  EnergySplit split;
  split.runs.resize(std::size_t(parts));
  split.work.assign(std::size_t(parts), 0.0);
  double total = 0.0;
  for (std::size_t b = 0; b < count; ++b) total += blocks[b].count * threadedNs(*blocks[b].type, flags);
  double first = (total + (parts - 1) * kWakeNs) / parts;
  if (first >= total) first = total / parts;
  const double other = parts > 1 ? (total - first) / (parts - 1) : 0.0;
  int part = 0;
  double limit = first, sum = 0.0;
  for (std::size_t b = 0; b < count; ++b) {
    const double cost = threadedNs(*blocks[b].type, flags);
    int e = 0;
    while (e < blocks[b].count) {
      int take = blocks[b].count - e;
      if (part < parts - 1) take = std::min(take, std::max(0, static_cast<int>(std::ceil((limit - sum) / cost))));
      if (take > 0) {
        split.runs[size_t(part)].push_back({b, e, take});
        split.work[size_t(part)] += take * cost;
        sum += take * cost;
        e += take;
      }
      if (e < blocks[b].count) ++part, limit += other;  // this part is full
    }
  }
  return split;
}

ThreadedPassEstimate estimatePass(const std::vector<ElementBlock>& blocks, std::size_t count, const PassWork& w,
                                  const OwnedPlan& plan, int threads, int flags) {
  const double sum = (flags & kPassEnergy) ? kSumNs * w.count : 0.0;
  ThreadedPassEstimate est;
  est.serial = w.elements;
  // Owned: each part's share of the pass after its thread starts, then the energies' sums.
  if (w.contributions > 0.0) {
    for (std::size_t p = 0; p < plan.work.size(); ++p)
      est.owned = std::max(est.owned, plan.work[p] + (p == 0 ? 0.0 : kWakeNs));
  } else {
    const EnergySplit split = splitEnergyPass(blocks, count, threads, flags);
    for (std::size_t p = 0; p < split.work.size(); ++p)
      est.owned = std::max(est.owned, split.work[p] + (p == 0 ? 0.0 : kWakeNs));
  }
  est.owned += kDispatchNs + sum;
  // Buffered: chunks taken by whichever thread is free (a worker from kWakeNs on), then the
  // gather the same way: each phase (its work + one wake-up) / threads.
  const double shared = w.elements + kSharedNs * w.count;
  const double gather = w.contributions > 0.0 ? kDispatchNs + (kGatherNs * w.contributions + kWakeNs) / threads : 0.0;
  est.buffered = kDispatchNs + (shared + kBufferNs * w.contributions + kWakeNs) / threads + gather + sum;
  const double best = std::min(est.owned, est.buffered);
  est.path = best > kThreadedGain * est.serial ? ThreadedPassPath::Serial
             : est.owned <= est.buffered       ? ThreadedPassPath::Owned
                                               : ThreadedPassPath::Buffered;
  est.serial *= 1e-9, est.owned *= 1e-9, est.buffered *= 1e-9;
  return est;
}

}  // namespace threaded_pass

ThreadedPassEstimate estimateThreadedPass(const SceneData& scene, int flags, int threads) {
  const std::size_t count = threaded_pass::threadedBlocks(scene.blocks(), flags);
  const threaded_pass::PassWork work = threaded_pass::passWork(scene.blocks(), count, flags);
  if (threads <= 1 || work.count == 0) {
    ThreadedPassEstimate est;
    est.serial = est.owned = est.buffered = 1e-9 * work.elements;
    return est;
  }
  return threaded_pass::estimatePass(scene.blocks(), count, work, threaded_pass::makeOwnedPlan(scene, count, threads),
                                     threads, flags);
}

}  // namespace stabint
