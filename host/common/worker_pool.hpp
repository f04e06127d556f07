#pragma once
// The threads the CPU side of the library works on: the CPU reference's element passes and the
// host's global solve (docs/method.md, "Threads on the CPU"). Every use writes disjoint outputs
// per task and combines them in a fixed order afterwards, so results are the same bit for bit
// for any thread count: the thread count is a speed setting, never a numerical one.
#include <cstddef>
#include <functional>
#include <vector>

namespace stabint {

/// Threads used (the calling thread included). Default: the STABINT_THREADS environment variable
/// when it holds a positive integer, else std::thread::hardware_concurrency(); at least 1.
int cpuThreads();
/// Sets the thread count for the whole process (1: everything on the calling thread). Takes
/// effect at the next parallelFor; workers are started lazily and kept.
void setCpuThreads(int threads);

/// Runs task(i) for every i in [0, tasks) on up to cpuThreads() threads, the caller being one of
/// them, and returns when all have finished. Tasks are handed out in order to whichever thread is
/// free, so a task must not depend on which thread runs it or on the other tasks. A call made
/// while another thread's call is running (two simulators stepped from two threads) runs its
/// tasks on its own thread. Having run its tasks, the calling thread waits awake (up to 200 us)
/// for workers still running theirs before it sleeps: waking it would take longer.
void parallelFor(int tasks, const std::function<void(int)>& task);

/// item(i) for every i in [0, work.size() - 1) on cpuThreads() threads, each thread a contiguous
/// run of items of about equal work (`work` is the prefix sums: item i costs work[i + 1] - work[i]),
/// the runs in order. For items that write disjoint outputs and may go to any thread (a batch's
/// scenes): the results are the serial loop's.
void parallelForRuns(const std::vector<double>& work, const std::function<void(std::size_t)>& item);

}  // namespace stabint
