#pragma once
// stabint-run's progress on standard error. On a terminal: one line redrawn in place, a bar with
// the frames done, frames per second and the time left, at most 10 times a second. Otherwise (a
// pipe, a file, a CI log): a plain line every second, "stabint-run: frame k/N, x ms/frame", so
// that a log reads line by line.
#include "cli.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>

namespace stabint_run {

class Progress {
 public:
  using Clock = std::chrono::steady_clock;

  Progress(int frames, bool quiet)
      : frames_(frames), quiet_(quiet), bar_(!quiet && ::isatty(STDERR_FILENO) == 1), start_(Clock::now()) {
    last_ = start_;
  }
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  ~Progress() { end(); }

  // After frame `frame` (1-based) is done.
  void frame(int frame) {
    if (quiet_) return;
    const auto now = Clock::now();
    if (bar_) {
      if (now - last_ >= std::chrono::milliseconds(100) || frame == frames_) {
        draw(frame, seconds(now));
        last_ = now;
      }
    } else if (now - last_ >= std::chrono::seconds(1)) {
      std::cerr << kProgram << ": frame " << frame << "/" << frames_ << ", " << 1e3 * seconds(now) / frame
                << " ms/frame\n";
      last_ = now;
    }
  }

  // Ends the bar's line, so that what is printed next starts on its own line.
  void end() {
    if (drawn_) std::cerr << "\n" << std::flush;
    drawn_ = false;
  }

  // Seconds since the start.
  double elapsed() const { return seconds(Clock::now()); }

 private:
  double seconds(Clock::time_point now) const { return std::chrono::duration<double>(now - start_).count(); }

  void draw(int frame, double elapsed) {
    constexpr int kWidth = 30;
    const double done = frames_ > 0 ? static_cast<double>(frame) / frames_ : 1.0;
    const int filled = static_cast<int>(done * kWidth);
    const double fps = elapsed > 0.0 ? frame / elapsed : 0.0;
    const double left = fps > 0.0 ? (frames_ - frame) / fps : 0.0;
    char line[160];
    std::snprintf(line, sizeof(line), "\r%s: [%s%s] %d/%d frames, %.1f fps, ETA %s\033[K", kProgram,
                  std::string(filled, '#').c_str(), std::string(kWidth - filled, '.').c_str(), frame, frames_, fps,
                  duration(left).c_str());
    std::cerr << line << std::flush;
    drawn_ = true;
  }

  static std::string duration(double seconds) {
    char text[32];
    const long s = static_cast<long>(seconds + 0.5);
    if (s >= 3600) {
      std::snprintf(text, sizeof(text), "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
    } else {
      std::snprintf(text, sizeof(text), "%ld:%02ld", s / 60, s % 60);
    }
    return text;
  }

  int frames_;
  bool quiet_;
  bool bar_;
  bool drawn_ = false;
  Clock::time_point start_;
  Clock::time_point last_;
};

}  // namespace stabint_run
