#include "cpu/cpu_backend.hpp"

#include "cpu/worker_pool.hpp"

#include "scene/scene_data.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cmath>
#include <limits>
#include <vector>

namespace stabint {
namespace {

using Clock = std::chrono::steady_clock;
struct Run {  // consecutive elements of one block
  size_t block;
  int first, count;
};
std::atomic<ThreadedPassPath> forced_path{ThreadedPassPath::Auto};
thread_local ThreadedPassPath last_pass_path = ThreadedPassPath::Serial;

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// ---- which passes go on threads, and how (docs/method.md section 12) ---------------------------
// The cost model, in nanoseconds, measured on the 2-core development VM (bench/bench_thread_pass.cpp;
// docs/benchmarks.md, "Threads in the element passes"). On one thread a kind's element costs its
// ElementType::elementCost (Kind::kElementNs), less kScatterNs per contribution in a pass that
// writes none (an energy pass). On threads:
//   kDispatchNs  what a parallelFor costs the calling thread before its first task (waking the
//                workers: a system call)
//   kWakeNs      how much later than the calling thread a sleeping worker starts its first task
//                (thread_pass_wake measures the two together)
//   kSharedNs    what each element costs more on one of two threads working at once than alone
//                (the memory traffic the cores share): fitted to the spring cloths' passes
//   kChainNs     one stored energy added to its block's sum on the calling thread afterwards (a
//                chain of dependent additions, which a single-threaded pass overlaps with its work)
//   kBufferNs, kGatherNs  a contribution's extra write to the buffer and its read in the gather
// A pass goes on threads only when its estimated time there is at most kThreadedGain of its
// estimated time on one thread: a margin for the estimates, and for a second core that the
// machine's other work takes now and then.
constexpr double kScatterNs = 1.3;
constexpr double kDispatchNs = 10'000.0;
constexpr double kWakeNs = 20'000.0;
constexpr double kSharedNs = 1.2;
constexpr double kChainNs = 0.8;
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

// The leading blocks a threaded path can take: those whose types give per-element results and
// owned results (all but contact; pins come after contact).
size_t threadedBlocks(const std::vector<ElementBlock>& blocks, int flags) {
  static const Eigen::MatrixX3d none;
  size_t count = 0;
  for (; count < blocks.size(); ++count) {
    const ElementBlock& b = blocks[count];
    if (!b.type->elementResults(b, b.params, none, 0, 0, flags, nullptr, nullptr) ||
        !b.type->ownedResults(b, b.params, none, 0, 0, flags, 0, 0, nullptr, nullptr))
      break;
  }
  return count;
}

// A pass's single-threaded cost over blocks [0, count): its elements at their kinds' local-step
// cost, less kScatterNs per contribution in a pass that writes none (an energy pass); and what
// it writes.
struct PassWork {
  double elements = 0.0;       // ns on one thread
  double contributions = 0.0;  // written by the pass
  double count = 0.0;          // elements
};
PassWork passWork(const std::vector<ElementBlock>& blocks, size_t count, int flags) {
  const bool write = (flags & (kPassProjection | kPassForce)) != 0;
  PassWork w;
  for (size_t b = 0; b < count; ++b) {
    w.elements += blocks[b].count * elementNs(*blocks[b].type, flags);
    if (write) w.contributions += double(blocks[b].count) * blocks[b].type->shape().vertices;
    w.count += blocks[b].count;
  }
  return w;
}

// False when even a perfect split over threads that all start at once would not pay.
bool mayPay(const PassWork& w, int threads) {
  return (w.elements + kSharedNs * w.count) / threads + kDispatchNs <= kThreadedGain * w.elements;
}

// The Owned path's split of blocks [0, count) over `parts` threads: contiguous vertex ranges,
// each element's estimated local-step cost shared among its vertices, such that all parts would
// end together when part 0 (the calling thread's: it takes the first task at once) starts
// kWakeNs before the others; and for each range the runs of consecutive elements with a vertex
// in it, with their cost (the elements across two ranges count in both).
struct OwnedPlan {
  std::vector<int> key;                // parts, then each block's count and revision
  std::vector<int> bounds;             // part p owns vertices [bounds[p], bounds[p + 1])
  std::vector<std::vector<Run>> runs;  // per part, in block and element order
  std::vector<double> work;            // per part: its elements' cost, ns
};
OwnedPlan makeOwnedPlan(const SceneData& scene, size_t count, int parts) {
  const std::vector<ElementBlock>& blocks = scene.blocks();
  OwnedPlan plan;
  plan.key = {parts};
  for (size_t b = 0; b < count; ++b) plan.key.insert(plan.key.end(), {blocks[b].count, blocks[b].revision});
  const int n = scene.numParticles();
  std::vector<double> work(static_cast<size_t>(n), 0.0);
  double total = 0.0;
  for (size_t b = 0; b < count; ++b) {
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
  plan.bounds.assign(size_t(parts) + 1, n);
  plan.bounds[0] = 0;
  double sum = 0.0;
  int part = 1;
  for (int v = 0; v < n && part < parts; ++v) {
    sum += work[size_t(v)];
    while (part < parts && sum >= first + (part - 1) * other) plan.bounds[size_t(part++)] = v + 1;
  }
  plan.runs.resize(size_t(parts));
  plan.work.assign(size_t(parts), 0.0);
  for (int p = 0; p < parts; ++p) {
    const int lo = plan.bounds[size_t(p)], hi = plan.bounds[size_t(p) + 1];
    std::vector<Run>& runs = plan.runs[size_t(p)];
    for (size_t b = 0; b < count; ++b) {
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

// The Owned path of an energy pass (no contributions, so no vertices to own): `parts` contiguous
// ranges of the elements, blocks in order, part 0 larger by kWakeNs as in OwnedPlan. The piece
// of a block that starts at its first element is summed as the single-threaded pass sums it
// (passRange: the same chain of additions, overlapped with the work); the other pieces store
// their elements' energies, which the calling thread adds on in element order afterwards.
struct EnergySplit {
  std::vector<std::vector<Run>> runs;  // per part
  std::vector<double> work;            // per part, ns
  double stored = 0.0;                 // elements outside the leading pieces
};
EnergySplit splitEnergyPass(const std::vector<ElementBlock>& blocks, size_t count, int parts, int flags) {
  EnergySplit split;
  split.runs.resize(size_t(parts));
  split.work.assign(size_t(parts), 0.0);
  double total = 0.0;
  for (size_t b = 0; b < count; ++b) total += blocks[b].count * threadedNs(*blocks[b].type, flags);
  double first = (total + (parts - 1) * kWakeNs) / parts;
  if (first >= total) first = total / parts;
  const double other = parts > 1 ? (total - first) / (parts - 1) : 0.0;
  int part = 0;
  double limit = first, sum = 0.0;
  for (size_t b = 0; b < count; ++b) {
    const double cost = threadedNs(*blocks[b].type, flags);
    int e = 0;
    while (e < blocks[b].count) {
      int take = blocks[b].count - e;
      if (part < parts - 1) take = std::min(take, std::max(0, static_cast<int>(std::ceil((limit - sum) / cost))));
      if (take > 0) {
        split.runs[size_t(part)].push_back({b, e, take});
        split.work[size_t(part)] += take * cost;
        sum += take * cost;
        if (e > 0) split.stored += take;
        e += take;
      }
      if (e < blocks[b].count) ++part, limit += other;  // this part is full
    }
  }
  return split;
}

// The estimated time of a pass on one thread and on `threads` by each path, and the path that
// Auto takes: the faster threaded one when it is at most kThreadedGain of one thread's time.
ThreadedPassEstimate estimatePass(const std::vector<ElementBlock>& blocks, size_t count, const PassWork& w,
                                  const OwnedPlan& plan, int threads, int flags) {
  const double chain = (flags & kPassEnergy) ? kChainNs * w.count : 0.0;
  ThreadedPassEstimate est;
  est.serial = w.elements;
  // Owned: each part's share of the pass after its thread starts, then the energies it stored.
  if (w.contributions > 0.0) {
    for (size_t p = 0; p < plan.work.size(); ++p)
      est.owned = std::max(est.owned, plan.work[p] + (p == 0 ? 0.0 : kWakeNs));
    est.owned += kDispatchNs + chain;
  } else {
    const EnergySplit split = splitEnergyPass(blocks, count, threads, flags);
    for (size_t p = 0; p < split.work.size(); ++p)
      est.owned = std::max(est.owned, split.work[p] + (p == 0 ? 0.0 : kWakeNs));
    est.owned += kDispatchNs + kChainNs * split.stored;
  }
  // Buffered: chunks taken by whichever thread is free (a worker from kWakeNs on), then the
  // gather the same way: each phase (its work + one wake-up) / threads.
  const double shared = w.elements + kSharedNs * w.count;
  const double gather = w.contributions > 0.0 ? kDispatchNs + (kGatherNs * w.contributions + kWakeNs) / threads : 0.0;
  est.buffered = kDispatchNs + (shared + kBufferNs * w.contributions + kWakeNs) / threads + gather + chain;
  const double best = std::min(est.owned, est.buffered);
  est.path = best > kThreadedGain * est.serial ? ThreadedPassPath::Serial
             : est.owned <= est.buffered       ? ThreadedPassPath::Owned
                                               : ThreadedPassPath::Buffered;
  est.serial *= 1e-9, est.owned *= 1e-9, est.buffered *= 1e-9;
  return est;
}

class CpuBackend final : public Backend {
 public:
  CpuBackend(const SceneData& scene, int num_slots)
      : scene_(scene),
        slots_(num_slots, Eigen::MatrixX3d::Zero(scene.numParticles(), 3)),
        params_(scene.blocks().size()) {}

  void write(int slot, const Eigen::MatrixX3d& host) override { slots_[slot] = host; }
  void read(int slot, Eigen::MatrixX3d& host) override { host = slots_[slot]; }
  void copy(int dst, int src) override { slots_[dst] = slots_[src]; }
  void combine(int dst, double a, int x, double b, int y) override { slots_[dst] = a * slots_[x] + b * slots_[y]; }
  double massDot(int a, int b) override {
    return (slots_[a].cwiseProduct(slots_[b]).rowwise().sum().array() * scene_.masses().array()).sum();
  }

  PotentialEnergy potential(int slot, double t) override {
    const auto start = Clock::now();
    const PotentialEnergy e = elementPass(slots_[slot], t, kPassEnergy, nullptr);
    times_.energy += secondsSince(start);
    return e;
  }

  void accelerations(int dst, int slot, double t) override {
    const auto start = Clock::now();
    // f = f_ext + sum_e w_e A_e^T (p_e - A_e x)
    Eigen::MatrixX3d f = externalForces(t);
    elementPass(slots_[slot], t, kPassForce, &f);
    slots_[dst] = f.array().colwise() / scene_.masses().array();
    times_.local += secondsSince(start);
  }

  void localStepRhs(int x_slot, int y_slot, double c, double t, Eigen::MatrixX3d& rhs,
                    PotentialEnergy* energy_at_x) override {
    const auto start = Clock::now();
    rhs = (c * slots_[y_slot]).array().colwise() * scene_.masses().array();
    rhs += externalForces(t);
    const int flags = kPassProjection | (energy_at_x ? kPassEnergy : 0);
    const PotentialEnergy e = elementPass(slots_[x_slot], t, flags, &rhs);
    if (energy_at_x) *energy_at_x = e;
    times_.local += secondsSince(start);
  }

  void localStepGradient(int x_slot, int y_slot, double c, double t, Eigen::MatrixX3d& gradient,
                         PotentialEnergy* energy_at_x) override {
    const auto start = Clock::now();
    // The kernel's order of operations (gather_gradient): c m (x - y) - f_ext - sum of forces.
    force_.setZero(scene_.numParticles(), 3);
    const int flags = kPassForce | (energy_at_x ? kPassEnergy : 0);
    const PotentialEnergy e = elementPass(slots_[x_slot], t, flags, &force_);
    gradient.resize(scene_.numParticles(), 3);
    gradient.array() = (slots_[x_slot] - slots_[y_slot]).array().colwise() * (c * scene_.masses().array()) -
                       externalForces(t).array() - force_.array();
    if (energy_at_x) *energy_at_x = e;
    times_.local += secondsSince(start);
  }

  bool computesPerScene() const override { return true; }
  void setSegments(const std::vector<SceneSegment>& segments) override { segments_ = segments; }

  // Each segment's rows copied out first, so that the reduction runs over an `n_s by 3` matrix as
  // massDot's does over the scene alone's: the same order of additions, bit for bit.
  void massDots(int a, int b, std::vector<double>& out) override {
    const auto start = Clock::now();
    out.resize(segments_.size());
    for (std::size_t s = 0; s < segments_.size(); ++s) {
      const SceneSegment& seg = segments_[s];
      segment_a_ = slots_[a].middleRows(seg.first_particle, seg.num_particles);
      segment_b_ = slots_[b].middleRows(seg.first_particle, seg.num_particles);
      segment_m_ = scene_.masses().segment(seg.first_particle, seg.num_particles);
      out[s] = (segment_a_.cwiseProduct(segment_b_).rowwise().sum().array() * segment_m_.array()).sum();
    }
    times_.energy += secondsSince(start);
  }

  void potentials(int slot, double t, std::vector<PotentialEnergy>& out) override {
    if (segments_.size() == 1) {  // a batch of one: the whole pass, threaded as potential()'s
      out.assign(1, potential(slot, t));
      return;
    }
    const auto start = Clock::now();
    const Eigen::MatrixX3d& x = slots_[slot];
    const std::vector<ElementBlock>& blocks = scene_.blocks();
    const Eigen::MatrixX3d& f = externalForces(t);
    out.assign(segments_.size(), PotentialEnergy{});
    for (std::size_t s = 0; s < segments_.size(); ++s) {
      const SceneSegment& seg = segments_[s];
      PotentialEnergy& e = out[s];
      for (std::size_t b = 0; b < blocks.size(); ++b) {
        const ElementBlock& block = blocks[b];
        const int count = seg.num_elements[b];
        if (count == 0) continue;
        const double energy =
            block.type->passRange(block, paramsAt(b, t), x, seg.first_element[b], count, kPassEnergy, nullptr);
        (block.type->term() == EnergyTerm::Pins ? e.pins : e.internal) += energy;
      }
      segment_a_ = f.middleRows(seg.first_particle, seg.num_particles);
      segment_b_ = x.middleRows(seg.first_particle, seg.num_particles);
      e.external = -segment_a_.cwiseProduct(segment_b_).sum();
    }
    times_.energy += secondsSince(start);
  }

  std::string description() const override { return "CPU reference (double)"; }

 private:
  /// Every block in the order of the contribution numbering (so the scattered sums add in the
  /// order of the OpenCL gather), plus the external potential when energies are asked for.
  PotentialEnergy elementPass(const Eigen::MatrixX3d& x, double t, int flags, Eigen::MatrixX3d* out) {
    PotentialEnergy e;
    const std::vector<ElementBlock>& blocks = scene_.blocks();
    const size_t first_sequential = threadedPass(x, t, flags, out, e);
    for (size_t b = first_sequential; b < blocks.size(); ++b) {
      const ElementBlock& block = blocks[b];
      if (block.count == 0) continue;
      const double energy = block.type->pass(block, paramsAt(b, t), x, flags, out);
      (block.type->term() == EnergyTerm::Pins ? e.pins : e.internal) += energy;
    }
    if (flags & kPassEnergy) e.external = -externalForces(t).cwiseProduct(x).sum();
    return e;
  }

  /// The leading blocks that a threaded path can take (threadedBlocks) on cpuThreads() threads,
  /// when the path forced (setThreadedPassPath) or chosen (estimatePass) is not Serial; returns
  /// the first block it did not do (0 when it left the pass to the calling thread). Either path
  /// makes the additions passRange makes, in the same order, so the result is the single-threaded
  /// pass's bit for bit whatever the thread count and the path:
  ///   Buffered: fixed chunks of elements, taken by whichever thread is free, write each
  ///   element's energy and contributions to buffers (ElementType::elementResults); then each
  ///   vertex adds its contributions in contribution order (SceneData::csr, the OpenCL gather's
  ///   order, which is also the order in which the single-threaded pass scatters them), vertices
  ///   split over the threads. Two wake-ups, one extra write and read per contribution.
  ///   Owned: each thread owns a contiguous range of vertices (OwnedPlan) and runs, in element
  ///   order, every element with a vertex in its range, adding only the contributions to its own
  ///   vertices (ElementType::ownedResults). One wake-up, no buffer; the elements across two
  ///   ranges are computed on both.
  /// Either way each block's energy is then summed over its elements in element order on the
  /// calling thread.
  size_t threadedPass(const Eigen::MatrixX3d& x, double t, int flags, Eigen::MatrixX3d* out, PotentialEnergy& e) {
    last_pass_path = ThreadedPassPath::Serial;
    const std::vector<ElementBlock>& blocks = scene_.blocks();
    const int threads = cpuThreads();
    const ThreadedPassPath forced = threadedPassPath();
    if (threads <= 1 || forced == ThreadedPassPath::Serial) return 0;
    const size_t count = threadedBlocks(blocks, flags);
    int elements = 0;
    for (size_t b = 0; b < count; ++b) elements += blocks[b].count;
    if (elements == 0) return 0;
    ThreadedPassPath path = forced;
    if (path == ThreadedPassPath::Auto) {
      const PassWork work = passWork(blocks, count, flags);
      // Not even a perfect split onto threads that all start at once would pay: no plan needed.
      if (!mayPay(work, threads)) return 0;
      path = estimatePass(blocks, count, work, ownedPlan(count, threads), threads, flags).path;
    }
    if (path == ThreadedPassPath::Serial) return 0;
    block_params_.resize(count);
    element_base_.resize(count);
    int base = 0;
    for (size_t b = 0; b < count; ++b) {
      block_params_[b] = &paramsAt(b, t);
      element_base_[b] = base;
      base += blocks[b].count;
    }
    element_energies_.resize(static_cast<size_t>(elements));
    block_sums_.assign(count, 0.0);
    block_summed_.assign(count, 0);
    if (path == ThreadedPassPath::Owned) {
      ownedPass(x, count, threads, flags, out);
    } else {
      bufferedPass(x, count, flags, out);
    }
    for (size_t b = 0; b < count; ++b) {
      if (blocks[b].count == 0) continue;
      double energy = block_sums_[b];
      if (flags & kPassEnergy) {
        const double* energies = element_energies_.data() + element_base_[b];
        for (int i = block_summed_[b]; i < blocks[b].count; ++i) energy += energies[i];
      }
      (blocks[b].type->term() == EnergyTerm::Pins ? e.pins : e.internal) += energy;
    }
    last_pass_path = path;
    return count;
  }

  void bufferedPass(const Eigen::MatrixX3d& x, size_t count, int flags, Eigen::MatrixX3d* out) {
    const std::vector<ElementBlock>& blocks = scene_.blocks();
    const bool write = (flags & (kPassProjection | kPassForce)) != 0;
    int contributions_end = 0;
    chunks_.clear();
    for (size_t b = 0; b < count; ++b) {
      contributions_end = blocks[b].contribution_base + blocks[b].type->shape().vertices * blocks[b].count;
      for (int first = 0; first < blocks[b].count; first += kChunkElements) {
        chunks_.push_back({b, first, std::min(kChunkElements, blocks[b].count - first)});
      }
    }
    if (write) contributions_.resize(3 * static_cast<size_t>(contributions_end));
    parallelFor(static_cast<int>(chunks_.size()), [&](int i) {
      const Run& chunk = chunks_[static_cast<size_t>(i)];
      const ElementBlock& block = blocks[chunk.block];
      const int k = block.type->shape().vertices;
      block.type->elementResults(
          block, *block_params_[chunk.block], x, chunk.first, chunk.count, flags,
          element_energies_.data() + element_base_[chunk.block] + chunk.first,
          write ? contributions_.data() + 3 * (static_cast<size_t>(block.contribution_base) + size_t(k) * chunk.first)
                : nullptr);
    });
    if (!write) return;
    const ContributionCsr& csr = scene_.csr();
    const int n = scene_.numParticles();
    double* os = out->data();
    const double* c = contributions_.data();
    parallelFor((n + kChunkVertices - 1) / kChunkVertices, [&](int i) {
      const int end = std::min(n, (i + 1) * kChunkVertices);
      for (int v = i * kChunkVertices; v < end; ++v) {
        double o0 = os[v], o1 = os[n + v], o2 = os[2 * n + v];
        for (int j = csr.offsets[size_t(v)]; j < csr.offsets[size_t(v) + 1]; ++j) {
          const size_t index = static_cast<size_t>(csr.contributions[size_t(j)]);
          if (index >= static_cast<size_t>(contributions_end)) break;  // sorted: the rest are later blocks'
          o0 += c[3 * index];
          o1 += c[3 * index + 1];
          o2 += c[3 * index + 2];
        }
        os[v] = o0;
        os[n + v] = o1;
        os[2 * n + v] = o2;
      }
    });
  }

  void ownedPass(const Eigen::MatrixX3d& x, size_t count, int threads, int flags, Eigen::MatrixX3d* out) {
    const std::vector<ElementBlock>& blocks = scene_.blocks();
    if (!(flags & (kPassProjection | kPassForce))) {
      const EnergySplit split = splitEnergyPass(blocks, count, threads, flags);
      parallelFor(threads, [&](int part) {
        for (const Run& run : split.runs[size_t(part)]) {
          const ElementBlock& block = blocks[run.block];
          const std::vector<double>& params = *block_params_[run.block];
          if (run.first == 0) {
            block_sums_[run.block] = block.type->passRange(block, params, x, 0, run.count, flags, nullptr);
            block_summed_[run.block] = run.count;
          } else {
            block.type->elementResults(block, params, x, run.first, run.count, flags,
                                       element_energies_.data() + element_base_[run.block] + run.first, nullptr);
          }
        }
      });
      return;
    }
    const OwnedPlan& plan = ownedPlan(count, threads);
    parallelFor(threads, [&](int part) {
      const int lo = plan.bounds[size_t(part)], hi = plan.bounds[size_t(part) + 1];
      for (const Run& run : plan.runs[size_t(part)]) {
        const ElementBlock& block = blocks[run.block];
        block.type->ownedResults(block, *block_params_[run.block], x, run.first, run.count, flags, lo, hi, out,
                                 element_energies_.data() + element_base_[run.block] + run.first);
      }
    });
  }

  // The Owned path's plan for blocks [0, count) on `parts` threads, made once and kept until the
  // thread count or a block changes.
  const OwnedPlan& ownedPlan(size_t count, int parts) {
    const std::vector<ElementBlock>& blocks = scene_.blocks();
    bool same = plan_.key.size() == 1 + 2 * count && plan_.key[0] == parts;
    for (size_t b = 0; same && b < count; ++b)
      same = plan_.key[1 + 2 * b] == blocks[b].count && plan_.key[2 + 2 * b] == blocks[b].revision;
    if (!same) plan_ = makeOwnedPlan(scene_, count, parts);
    return plan_;
  }

  // Params of block b at time t: the block's own unless its type depends on time; cached
  // because the driver asks for the same t many times per step.
  const std::vector<double>& paramsAt(size_t b, double t) {
    const ElementBlock& block = scene_.blocks()[b];
    if (!block.type->timeDependent(scene_)) return block.params;
    TimedParams& cached = params_[b];
    if (!cached.key.matches(t, scene_.forcingVersion())) {
      block.type->paramsAt(scene_, t, cached.values);
      cached.key = {t, scene_.forcingVersion()};
    }
    return cached.values;
  }

  // Forcing at time t, cached like the params.
  const Eigen::MatrixX3d& externalForces(double t) {
    if (!external_key_.matches(t, scene_.forcingVersion())) {
      scene_.externalForces(t, external_);
      external_key_ = {t, scene_.forcingVersion()};
    }
    return external_;
  }

  struct ForcingKey {
    double time = std::numeric_limits<double>::quiet_NaN();
    int version = -1;
    bool matches(double t, int v) const { return t == time && v == version; }
  };
  struct TimedParams {
    std::vector<double> values;
    ForcingKey key;
  };

  // Buffered: chunks are a few microseconds of work each.
  static constexpr int kChunkElements = 512;
  static constexpr int kChunkVertices = 1024;

  const SceneData& scene_;
  std::vector<Eigen::MatrixX3d> slots_;
  std::vector<TimedParams> params_;  // per block
  Eigen::MatrixX3d external_;
  ForcingKey external_key_;
  std::vector<SceneSegment> segments_;
  Eigen::MatrixX3d segment_a_, segment_b_;  // one segment's rows (massDots, potentials)
  Eigen::VectorXd segment_m_;
  // threadedPass's work list and buffers, reused from pass to pass.
  std::vector<Run> chunks_;
  std::vector<const std::vector<double>*> block_params_;
  std::vector<int> element_base_;
  std::vector<double> element_energies_, contributions_;
  Eigen::MatrixX3d force_;          // localStepGradient's forces, reused
  std::vector<double> block_sums_;  // per block: the sum of its first block_summed_ energies
  std::vector<int> block_summed_;
  OwnedPlan plan_;
};

}  // namespace

ThreadedPassEstimate estimateThreadedPass(const SceneData& scene, int flags, int threads) {
  const size_t count = threadedBlocks(scene.blocks(), flags);
  const PassWork work = passWork(scene.blocks(), count, flags);
  if (threads <= 1 || work.count == 0) {
    ThreadedPassEstimate est;
    est.serial = est.owned = est.buffered = 1e-9 * work.elements;
    return est;
  }
  return estimatePass(scene.blocks(), count, work, makeOwnedPlan(scene, count, threads), threads, flags);
}

void setThreadedPassPath(ThreadedPassPath path) { forced_path.store(path); }
ThreadedPassPath threadedPassPath() { return forced_path.load(); }
ThreadedPassPath lastPassPath() { return last_pass_path; }

std::unique_ptr<Backend> makeCpuBackend(const SceneData& scene, int num_slots) {
  return std::make_unique<CpuBackend>(scene, num_slots);
}

}  // namespace stabint
