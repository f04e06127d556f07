// `prefetch`: every reference trajectory that `all` reads (the IM h/16 references and the
// small-step motion references), computed before the experiments and two at a time.
//
// The references are about 420 s of one core's work, one after another, in a main job run on the
// 2-core development VM. Each is a run on the CPU reference backend whose result does not depend
// on the thread it runs on (docs/method.md, "Threads on the CPU": a call that finds the worker
// pool busy runs on its own thread, and every path gives the serial result bit for bit), so two
// threads write the same cache files in about half the time. Computing them first keeps them out
// of the timed experiments, whose ms-per-frame figures then see an otherwise idle machine.
#include "study.hpp"

#include <atomic>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace study {

void runPrefetch(const StudyOptions& options) {
  // What table, reference, sweep, energy and motion read, the longest first (the stiff drag's
  // motion reference is about 100 s of the 420 s, the others 1-55 s) so that the two threads end
  // together. A reference left out here is computed by the subcommand that reads it: slower, the
  // same result.
  std::vector<std::function<void()>> jobs;
  const auto motion = [&](const StudyScene& s) { jobs.push_back([s, &options] { motionReference(s, options); }); };
  const auto accuracy = [&](const StudyScene& s) {
    jobs.push_back([s, &options] { loadOrComputeReference(s, options); });
  };
  motion(stiffDragScene());
  motion(clothScene());
  accuracy(triangleClothScene());
  motion(triangleClothScene());
  for (double f : kHandleFrequencies) motion(handleClothScene(f));
  motion(clothScene(kStiffClothStretch));
  motion(chainScene());
  accuracy(clothScene());
  accuracy(tetBarScene());
  motion(tetBarScene());

  ensureDirectory(joinPath(options.out, "cache"));  // before the threads, which both write there
  std::atomic<std::size_t> next{0};
  std::mutex failure_mutex;
  std::exception_ptr failure;
  const auto work = [&] {
    for (std::size_t j = next++; j < jobs.size(); j = next++) {
      try {
        jobs[j]();
      } catch (...) {
        const std::lock_guard<std::mutex> lock(failure_mutex);
        if (!failure) failure = std::current_exception();
        next = jobs.size();  // start nothing more
      }
    }
  };
  std::thread second(work);
  work();
  second.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace study
