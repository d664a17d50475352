#pragma once
// Progress display for long jobs (precompute, bench, long simulations).
// Writes to stderr; on a terminal it redraws one line, otherwise it prints a
// line per 10% so logs stay readable. Quiet mode prints nothing.
#include <chrono>
#include <string>

namespace sflsh {

class Progress {
 public:
  /// `total` units of work for the stage named `stage`.
  Progress(std::string stage, long total);
  ~Progress();
  /// Advance to `done` units (monotone). Cheap when called often.
  void update(long done);
  /// Marks the stage complete and prints the elapsed time.
  void finish();
  /// Seconds since construction.
  double elapsed_s() const;

  /// Global switch (the CLI's --quiet).
  static void set_quiet(bool quiet);
  static bool quiet();

 private:
  std::string stage_;
  long total_;
  long done_ = 0;
  int last_decile_ = -1;
  bool finished_ = false;
  bool tty_;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

/// Prints "stage: message" to stderr unless quiet (for one-off stage notes).
void log_info(const std::string& message);

}  // namespace sflsh
