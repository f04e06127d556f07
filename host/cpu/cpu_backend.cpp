#include "cpu/cpu_backend.hpp"

#include "cpu/threaded_pass.hpp"
#include "common/worker_pool.hpp"
#include "elements/energy_sum.hpp"

#include "scene/scene_data.hpp"
#include "scene/scene_view.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cmath>
#include <limits>
#include <vector>

namespace stabint {
namespace {

using namespace threaded_pass;
using Clock = std::chrono::steady_clock;
std::atomic<ThreadedPassPath> forced_path{ThreadedPassPath::Auto};
thread_local ThreadedPassPath last_pass_path = ThreadedPassPath::Serial;

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

class CpuBackend final : public Backend {
 public:
  CpuBackend(const SceneData& scene, const Forcing& forcing, int num_slots)
      : scene_(scene),
        forcing_(forcing),
        running_(scene, forcing),
        slots_(num_slots, Eigen::MatrixX3d::Zero(scene.numParticles(), 3)),
        params_(scene.blocks().size()) {}

  void write(int slot, const Eigen::MatrixX3d& host) override { slots_[slot] = host; }
  bool writesRows() const override { return true; }
  void writeRows(int slot, int first, const Eigen::MatrixX3d& rows) override {
    slots_[slot].middleRows(first, rows.rows()) = rows;
  }
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
    formGradient(x_slot, y_slot, c, t, gradient);
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

  void potentials(int slot, double t, std::vector<PotentialEnergy>& out, const std::vector<char>* which) override {
    if (segments_.size() == 1) {  // a batch of one: the whole pass, threaded as potential()'s
      out.assign(1, potential(slot, t));
      return;
    }
    const auto start = Clock::now();
    segmentPasses(slots_[slot], t, kPassEnergy, nullptr, out, which);
    times_.energy += secondsSince(start);
  }

  // A batch's L-BFGS: the force pass and every scene's energy at once, segment by segment.
  void localStepGradientPerScene(int x_slot, int y_slot, double c, double t, Eigen::MatrixX3d& gradient,
                                 std::vector<PotentialEnergy>& per_scene, const std::vector<char>* running) override {
    if (segments_.size() <= 1) {
      Backend::localStepGradientPerScene(x_slot, y_slot, c, t, gradient, per_scene);
      return;
    }
    const auto start = Clock::now();
    force_.setZero(scene_.numParticles(), 3);
    segmentPasses(slots_[x_slot], t, kPassForce | kPassEnergy, &force_, per_scene, running);
    formGradient(x_slot, y_slot, c, t, gradient);
    times_.local += secondsSince(start);
  }

  // A batch's Chebyshev or Anderson: the projections and every scene's energy at once.
  void localStepRhsPerScene(int x_slot, int y_slot, double c, double t, Eigen::MatrixX3d& rhs,
                            std::vector<PotentialEnergy>& per_scene, const std::vector<char>* running) override {
    if (segments_.size() <= 1) {
      Backend::localStepRhsPerScene(x_slot, y_slot, c, t, rhs, per_scene);
      return;
    }
    const auto start = Clock::now();
    rhs = (c * slots_[y_slot]).array().colwise() * scene_.masses().array();
    rhs += externalForces(t);
    segmentPasses(slots_[x_slot], t, kPassProjection | kPassEnergy, &rhs, per_scene, running);
    times_.local += secondsSince(start);
  }

  PotentialEnergy potentialOf(int segment, int slot, double t) override {
    if (segments_.size() == 1) return potential(slot, t);  // as potentials() for a batch of one
    const auto start = Clock::now();
    cacheBlockParams(t);
    const PotentialEnergy e = segmentPass(static_cast<std::size_t>(segment), slots_[slot], externalForces(t),
                                          kPassEnergy, nullptr, segment_a_, segment_b_);
    times_.energy += secondsSince(start);
    return e;
  }

  std::string description() const override { return "CPU reference (double)"; }

 private:
  /// The local step's gradient from the element forces in force_:
  /// g = c m (x - y) - f_ext - sum of forces (the kernel gather_gradient's order of operations).
  void formGradient(int x_slot, int y_slot, double c, double t, Eigen::MatrixX3d& gradient) {
    gradient.resize(scene_.numParticles(), 3);
    gradient.array() = (slots_[x_slot] - slots_[y_slot]).array().colwise() * (c * scene_.masses().array()) -
                       externalForces(t).array() - force_.array();
  }

  /// Segment s's elements and particles alone, in the order a backend of that scene alone sums
  /// them (bit for bit): `flags`' pass over each block's range of the segment (contributions into
  /// `out`'s rows of the segment, which no other segment's elements touch) and the external
  /// potential of its rows, copied out so that the reduction runs over an `n_s by 3` matrix as
  /// over the scene alone's. `rows_f`, `rows_x`: scratch of the calling thread.
  PotentialEnergy segmentPass(std::size_t s, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& external, int flags,
                              Eigen::MatrixX3d* out, Eigen::MatrixX3d& rows_f, Eigen::MatrixX3d& rows_x) const {
    const std::vector<ElementBlock>& blocks = scene_.blocks();
    const SceneSegment& seg = segments_[s];
    PotentialEnergy e;
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      const ElementBlock& block = blocks[b];
      const int count = seg.num_elements[b];
      if (count == 0) continue;
      const double energy = block.type->passRange(block, *block_params_[b], x, seg.first_element[b], count, flags, out);
      (block.type->term() == EnergyTerm::Pins ? e.pins : e.internal) += energy;
    }
    rows_f = external.middleRows(seg.first_particle, seg.num_particles);
    rows_x = x.middleRows(seg.first_particle, seg.num_particles);
    e.external = -rows_f.cwiseProduct(rows_x).sum();
    return e;
  }

  /// Every block's params at time t into block_params_, for segmentPass.
  void cacheBlockParams(double t) {
    block_params_.resize(scene_.blocks().size());
    for (std::size_t b = 0; b < block_params_.size(); ++b) block_params_[b] = &paramsAt(b, t);
  }

  /// segmentPass for every segment into per_scene (with `running`, the segments flagged alone). On
  /// threads each takes a contiguous run of segments (about equal element work): a segment's sums
  /// and contributions are the same on any thread, so the result is the serial pass's bit for bit.
  void segmentPasses(const Eigen::MatrixX3d& x, double t, int flags, Eigen::MatrixX3d* out,
                     std::vector<PotentialEnergy>& per_scene, const std::vector<char>* running = nullptr) {
    const std::vector<ElementBlock>& blocks = scene_.blocks();
    // The time-dependent params and forcing are cached on this thread before any worker reads them.
    cacheBlockParams(t);
    const Eigen::MatrixX3d& external = externalForces(t);
    const std::size_t segments = segments_.size();
    per_scene.resize(segments);
    const int threads = cpuThreads();
    auto runs = [&](std::size_t s) { return !running || (*running)[s]; };
    // Runs of segments of about equal work, by the elements' local-step cost (0 for a segment
    // that does not run).
    std::vector<double>& work = segment_work_;
    work.assign(segments + 1, 0.0);
    double all = 0.0;
    for (std::size_t s = 0; s < segments; ++s) {
      double w = 0.0;
      for (std::size_t b = 0; b < blocks.size(); ++b)
        w += segments_[s].num_elements[b] * std::max(blocks[b].type->elementCost(), 1.0);
      all += w;
      work[s + 1] = work[s] + (runs(s) ? w : 0.0);
    }
    // The threads must pay for the segments that run.
    PassWork pass = passWork(blocks, blocks.size(), flags);
    const double share = all > 0.0 ? work[segments] / all : 0.0;
    pass.elements *= share;
    pass.contributions *= share;
    pass.count *= share;
    const bool threaded =
        threads > 1 && threadedPassPath() != ThreadedPassPath::Serial && share > 0.0 && mayPay(pass, threads);
    if (!threaded) {
      for (std::size_t s = 0; s < segments; ++s)
        if (runs(s)) per_scene[s] = segmentPass(s, x, external, flags, out, segment_a_, segment_b_);
      return;
    }
    parallelForRuns(work, [&](std::size_t s) {
      if (!runs(s)) return;
      thread_local Eigen::MatrixX3d rows_f, rows_x;  // the segment's rows (no allocation per segment)
      per_scene[s] = segmentPass(s, x, external, flags, out, rows_f, rows_x);
    });
  }

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
  /// Either way each block's energy is then summed from the stored energies on the calling
  /// thread, by the rule every pass sums by (sumEnergies, elements/energy_sum.hpp).
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
    if (path == ThreadedPassPath::Owned) {
      ownedPass(x, count, threads, flags, out);
    } else {
      bufferedPass(x, count, flags, out);
    }
    for (size_t b = 0; b < count; ++b) {
      if (blocks[b].count == 0) continue;
      const double energy =
          (flags & kPassEnergy) ? sumEnergies(element_energies_.data() + element_base_[b], blocks[b].count) : 0.0;
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
          block.type->elementResults(block, *block_params_[run.block], x, run.first, run.count, flags,
                                     element_energies_.data() + element_base_[run.block] + run.first, nullptr);
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
  // because the driver asks for the same t many times per step, until the forcing or the block
  // changes (its weights carry into the timed params).
  const std::vector<double>& paramsAt(size_t b, double t) {
    const ElementBlock& block = scene_.blocks()[b];
    if (!block.type->timeDependent(running_)) return block.params;
    TimedParams& cached = params_[b];
    const ForcingKey key{t, forcing_.version(), block.revision, block.params_revision};
    if (!cached.key.matches(key)) {
      block.type->paramsAt(running_, t, cached.values);
      cached.key = key;
    }
    return cached.values;
  }

  // External forces at time t, cached like the params (by their own version: an element change
  // leaves them).
  const Eigen::MatrixX3d& externalForces(double t) {
    const ForcingKey key{t, forcing_.forcesVersion()};
    if (!external_key_.matches(key)) {
      forcing_.externalForces(t, external_);
      external_key_ = key;
    }
    return external_;
  }

  struct ForcingKey {
    double time = std::numeric_limits<double>::quiet_NaN();
    int version = -1;
    int block_revision = -1, params_revision = -1;
    bool matches(const ForcingKey& k) const {
      return k.time == time && k.version == version && k.block_revision == block_revision &&
             k.params_revision == params_revision;
    }
  };
  struct TimedParams {
    std::vector<double> values;
    ForcingKey key;
  };

  // Buffered: chunks are a few microseconds of work each.
  static constexpr int kChunkElements = 512;
  static constexpr int kChunkVertices = 1024;

  const SceneData& scene_;
  const Forcing& forcing_;
  const SceneView running_;  // what the element types read
  std::vector<Eigen::MatrixX3d> slots_;
  std::vector<TimedParams> params_;  // per block
  Eigen::MatrixX3d external_;
  ForcingKey external_key_;
  std::vector<SceneSegment> segments_;
  Eigen::MatrixX3d segment_a_, segment_b_;  // one segment's rows (massDots, potentials)
  std::vector<double> segment_work_;        // segmentPasses: the runs' prefix sums of work
  Eigen::VectorXd segment_m_;
  // threadedPass's work list and buffers, reused from pass to pass.
  std::vector<Run> chunks_;
  std::vector<const std::vector<double>*> block_params_;
  std::vector<int> element_base_;
  std::vector<double> element_energies_, contributions_;
  Eigen::MatrixX3d force_;  // localStepGradient's forces, reused
  OwnedPlan plan_;
};

}  // namespace

void setThreadedPassPath(ThreadedPassPath path) { forced_path.store(path); }
ThreadedPassPath threadedPassPath() { return forced_path.load(); }
ThreadedPassPath lastPassPath() { return last_pass_path; }

std::unique_ptr<Backend> makeCpuBackend(const SceneData& scene, const Forcing& forcing, int num_slots) {
  return std::make_unique<CpuBackend>(scene, forcing, num_slots);
}

}  // namespace stabint
