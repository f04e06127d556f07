#pragma once
// Which element passes of the CPU reference go on threads, and how (docs/method.md section 12): the
// cost model, in nanoseconds measured on the 2-core development VM (bench/bench_thread_pass.cpp;
// docs/benchmarks.md, "Threads in the element passes"), and the Owned path's splits. The passes
// themselves are CpuBackend's (cpu_backend.cpp).
#include "cpu/cpu_backend.hpp"
#include "elements/element_type.hpp"

#include <cstddef>
#include <vector>

namespace stabint {

class SceneData;

namespace threaded_pass {

struct Run {  // consecutive elements of one block
  std::size_t block;
  int first, count;
};

// A pass's single-threaded cost over blocks [0, count): its elements at their kinds' local-step
// cost, less a scatter's cost per contribution in a pass that writes none (an energy pass); and
// what it writes.
struct PassWork {
  double elements = 0.0;       // ns on one thread
  double contributions = 0.0;  // written by the pass
  double count = 0.0;          // elements
};

// The Owned path's split of blocks [0, count) over `parts` threads: contiguous vertex ranges,
// each element's estimated local-step cost shared among its vertices, such that all parts would
// end together when part 0 (the calling thread's: it takes the first task at once) starts a
// worker's wake-up before the others; and for each range the runs of consecutive elements with a
// vertex in it, with their cost (the elements across two ranges count in both).
struct OwnedPlan {
  std::vector<int> key;                // parts, then each block's count and revision
  std::vector<int> bounds;             // part p owns vertices [bounds[p], bounds[p + 1])
  std::vector<std::vector<Run>> runs;  // per part, in block and element order
  std::vector<double> work;            // per part: its elements' cost, ns
};

// The Owned path of an energy pass (no contributions, so no vertices to own): `parts` contiguous
// ranges of the elements, blocks in order, part 0 larger as in OwnedPlan. Every piece stores its
// elements' energies, which the calling thread sums afterwards (sumEnergies).
struct EnergySplit {
  std::vector<std::vector<Run>> runs;  // per part
  std::vector<double> work;            // per part, ns
};

/// The leading blocks a threaded path can take: those whose types give per-element results and
/// owned results (all but contact; pins come after contact).
std::size_t threadedBlocks(const std::vector<ElementBlock>& blocks, int flags);
PassWork passWork(const std::vector<ElementBlock>& blocks, std::size_t count, int flags);
/// False when even a perfect split over threads that all start at once would not pay.
bool mayPay(const PassWork& w, int threads);
OwnedPlan makeOwnedPlan(const SceneData& scene, std::size_t count, int parts);
EnergySplit splitEnergyPass(const std::vector<ElementBlock>& blocks, std::size_t count, int parts, int flags);
/// The estimated time of a pass on one thread and on `threads` by each path, and the path that
/// Auto takes: the faster threaded one when it is at most kThreadedGain of one thread's time.
ThreadedPassEstimate estimatePass(const std::vector<ElementBlock>& blocks, std::size_t count, const PassWork& w,
                                  const OwnedPlan& plan, int threads, int flags);

}  // namespace threaded_pass
}  // namespace stabint
