#pragma once
#include <time.h>

#include <chrono>

namespace sflsh {

/// Wall-clock stopwatch (steady clock).
class Timer {
 public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  void reset() { start_ = std::chrono::steady_clock::now(); }
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  double ms() const { return 1e3 * seconds(); }

 private:
  std::chrono::steady_clock::time_point start_;
};

/// CPU time of the calling thread (ms): what a benchmark on a shared machine
/// reports when other jobs' load would inflate wall time.
inline double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * double(t.tv_sec) + 1e-6 * double(t.tv_nsec);
}

}  // namespace sflsh
