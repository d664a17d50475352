#include "sflsh/core/progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace sflsh {
namespace {
bool g_quiet = false;
}

void Progress::set_quiet(bool q) { g_quiet = q; }
bool Progress::quiet() { return g_quiet; }

Progress::Progress(std::string stage, long total)
    : stage_(std::move(stage)), total_(total > 0 ? total : 1), tty_(isatty(fileno(stderr)) != 0) {
  start_ = last_draw_ = std::chrono::steady_clock::now();
}

Progress::~Progress() {
  if (!finished_ && tty_ && !g_quiet) std::fprintf(stderr, "\n");
}

double Progress::elapsed_s() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::update(long done) {
  if (g_quiet || finished_) return;
  done_ = done;
  const double frac = std::min(1.0, double(done_) / double(total_));
  if (tty_) {
    auto now = std::chrono::steady_clock::now();
    if (now - last_draw_ < std::chrono::milliseconds(100) && done_ < total_) return;
    last_draw_ = now;
    std::fprintf(stderr, "\r  %-28s %5.1f%%  %7.1f s", stage_.c_str(), 100.0 * frac, elapsed_s());
    std::fflush(stderr);
  } else {
    const int decile = int(frac * 10.0);
    if (decile > last_decile_ && decile < 10) {
      last_decile_ = decile;
      std::fprintf(stderr, "  %-28s %3d%%  %7.1f s\n", stage_.c_str(), decile * 10, elapsed_s());
    }
  }
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (g_quiet) return;
  std::fprintf(stderr, "%s  %-28s done   %7.2f s\n", tty_ ? "\r" : "", stage_.c_str(), elapsed_s());
}

void log_info(const std::string& message) {
  if (!g_quiet) std::fprintf(stderr, "%s\n", message.c_str());
}

}  // namespace sflsh
