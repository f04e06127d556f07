#pragma once
// CPU reference backend: the same operations as the OpenCL backend in plain double-precision
// C++ over Eigen arrays. It is the oracle every OpenCL result is checked against.
#include "backend/backend.hpp"

#include <memory>

namespace stabint {

class Forcing;
class SceneData;

/// The CPU reference of `scene` driven by `forcing` (both must outlive it).
std::unique_ptr<Backend> makeCpuBackend(const SceneData& scene, const Forcing& forcing, int num_slots);

/// How the CPU reference splits an element pass over cpuThreads() threads (docs/method.md
/// section 12). Every path gives the single-threaded pass's results bit for bit, so the choice is
/// one of speed only.
enum class ThreadedPassPath {
  Auto,      ///< the default: by the pass's estimated work (threaded_pass.cpp, estimatePass)
  Serial,    ///< on the calling thread
  Buffered,  ///< element results to buffers, then gathered per vertex through the CSR
  Owned,     ///< each thread owns a range of vertices and runs every element touching it
};
/// Forces a path for every pass in the process (tests and benchmarks; Auto restores the rule).
/// A forced threaded path is taken whatever the size, on cpuThreads() > 1 threads.
void setThreadedPassPath(ThreadedPassPath path);
ThreadedPassPath threadedPassPath();
/// The path the calling thread's last element pass took (Serial, Buffered or Owned).
ThreadedPassPath lastPassPath();

/// The cost model's estimates for one pass with `flags` (PassFlags) over the blocks a threaded
/// path can take, in seconds, and the path Auto takes with `threads` threads (benchmarks set them
/// beside the measured times).
struct ThreadedPassEstimate {
  double serial = 0.0, owned = 0.0, buffered = 0.0;
  ThreadedPassPath path = ThreadedPassPath::Serial;
};
ThreadedPassEstimate estimateThreadedPass(const SceneData& scene, int flags, int threads);

}  // namespace stabint
