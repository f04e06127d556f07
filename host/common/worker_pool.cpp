#include "common/worker_pool.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <mutex>
#include <thread>
#include <vector>

namespace stabint {
namespace {

int defaultThreads() {
  if (const char* env = std::getenv("STABINT_THREADS")) {
    char* end = nullptr;
    const long value = std::strtol(env, &end, 10);
    if (end != env && *end == '\0' && value > 0) return static_cast<int>(std::min(value, 256L));
  }
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

std::atomic<int>& threadSetting() {
  static std::atomic<int> threads{defaultThreads()};
  return threads;
}

// A pause in a spin-wait loop (the x86 PAUSE instruction: lets the core's other work run and
// keeps the loop from flooding the memory system).
inline void spinPause() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#else
  std::this_thread::yield();
#endif
}

// Workers sleep on a condition variable between calls. A call publishes a job (generation
// number, task function, count), runs tasks itself, then closes the job and waits for the
// workers that joined it to leave: a worker that wakes after the job was closed does not join,
// so no worker ever sees the task function of a call that has returned.
class WorkerPool {
 public:
  ~WorkerPool() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& worker : workers_) worker.join();
  }

  void run(int tasks, int threads, const std::function<void(int)>& task) {
    std::unique_lock<std::mutex> busy(busy_, std::try_to_lock);
    if (!busy.owns_lock() || threads <= 1 || tasks <= 1) {
      for (int i = 0; i < tasks; ++i) task(i);
      return;
    }
    while (static_cast<int>(workers_.size()) < threads - 1) workers_.emplace_back([this] { work(); });
    {
      std::lock_guard<std::mutex> lock(mutex_);
      task_ = &task;
      tasks_ = tasks;
      next_.store(0);
      joinable_ = threads - 1;
      open_ = true;
      ++generation_;
    }
    wake_.notify_all();
    runTasks(task);
    std::unique_lock<std::mutex> lock(mutex_);
    open_ = false;
    if (inside_.load() != 0) {
      // Workers still run tasks: wait for them awake a while before sleeping on left_, since a
      // sleeping thread takes about as long to wake as a pass's share of work (30-40 us on the
      // development VM); the tasks of a call are sized to end together.
      lock.unlock();
      const auto until = std::chrono::steady_clock::now() + kSpin;
      while (inside_.load() != 0 && std::chrono::steady_clock::now() < until) spinPause();
      lock.lock();
    }
    left_.wait(lock, [this] { return inside_.load() == 0; });
    task_ = nullptr;
  }

 private:
  void runTasks(const std::function<void(int)>& task) {
    for (int i = next_.fetch_add(1); i < tasks_; i = next_.fetch_add(1)) task(i);
  }

  void work() {
    unsigned long seen = 0;
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [&] { return stop_ || (generation_ != seen && open_ && joinable_ > 0); });
      if (stop_) return;
      seen = generation_;
      --joinable_;
      ++inside_;
      const std::function<void(int)>& task = *task_;
      lock.unlock();
      runTasks(task);
      lock.lock();
      if (--inside_ == 0) left_.notify_all();
    }
  }

  std::mutex busy_;   // one call at a time; others run on their own thread
  std::mutex mutex_;  // guards the job fields below and the worker bookkeeping
  std::condition_variable wake_, left_;
  std::vector<std::thread> workers_;
  const std::function<void(int)>* task_ = nullptr;
  int tasks_ = 0;
  std::atomic<int> next_{0};
  int joinable_ = 0;  // workers that may still join the open job (fewer when the setting dropped)
  // Workers running tasks of the current job; changed under mutex_, read without it while the
  // caller spins.
  std::atomic<int> inside_{0};
  // How long a call waits awake for its workers to finish before it sleeps.
  static constexpr std::chrono::microseconds kSpin{200};
  bool open_ = false;
  bool stop_ = false;
  unsigned long generation_ = 0;
};

WorkerPool& pool() {
  static WorkerPool instance;
  return instance;
}

}  // namespace

int cpuThreads() { return threadSetting().load(); }

void setCpuThreads(int threads) { threadSetting().store(std::max(1, threads)); }

void parallelFor(int tasks, const std::function<void(int)>& task) { pool().run(tasks, cpuThreads(), task); }

void parallelForRuns(const std::vector<double>& work, const std::function<void(std::size_t)>& item) {
  const std::size_t items = work.empty() ? 0 : work.size() - 1;
  const int threads = cpuThreads();
  std::vector<std::size_t> bounds(std::size_t(threads) + 1, items);
  bounds[0] = 0;
  for (int p = 1; p < threads; ++p)
    bounds[std::size_t(p)] = std::size_t(
        std::lower_bound(work.begin(), work.begin() + std::ptrdiff_t(items) + 1, work[items] * p / threads) -
        work.begin());
  parallelFor(threads, [&](int part) {
    for (std::size_t i = bounds[std::size_t(part)]; i < bounds[std::size_t(part) + 1]; ++i) item(i);
  });
}

}  // namespace stabint
