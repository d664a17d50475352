#include "sflsh/io/crash_isolation.hpp"

#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

#include "sflsh/core/error.hpp"

namespace sflsh::io {
namespace {
constexpr int kProbeRead = 0, kProbeThrew = 42;  // the child's exit codes
constexpr double kDefaultProbeSeconds = 120;

/// The child's time limit: SFLSH_READ_PROBE_SECONDS if it is a positive number, else 120 s.
double probe_seconds() {
  if (const char* env = std::getenv("SFLSH_READ_PROBE_SECONDS")) {
    char* end = nullptr;
    const double s = std::strtod(env, &end);
    if (end != env && *end == '\0' && std::isfinite(s) && s > 0) return s;
  }
  return kDefaultProbeSeconds;
}
}  // namespace

void probe_in_child_process(const std::string& what, const std::function<void()>& probe) {
  if (const char* env = std::getenv("SFLSH_READ_IN_PROCESS"); env && std::string(env) == "1") return;
  std::fflush(nullptr);  // nothing buffered is written twice
  const pid_t pid = fork();
  if (pid < 0) return;  // no process to spare: read in this one, as before
  if (pid == 0) {
    int code = kProbeRead;
    try {
      probe();
    } catch (...) {
      code = kProbeThrew;  // an ordinary error: the parent's own read reports it
    }
    _exit(code);  // no atexit handlers (libhdf5's) and no flush of the parent's buffers
  }
  // Wait, polling, so that a reader that loops on a damaged file is stopped: assimp's
  // PLY reader ran for minutes on a 542-byte file before its header was checked (fuzz.sh).
  const double limit = probe_seconds();
  const auto start = std::chrono::steady_clock::now();
  auto pause = std::chrono::microseconds(100);  // doubles up to 10 ms: a fast read waits little
  int status = 0;
  for (;;) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) return;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > limit) {
      kill(pid, SIGKILL);
      while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
      char seconds[32];
      std::snprintf(seconds, sizeof seconds, "%g", limit);
      fail(what, ": damaged file? parsing it did not finish within ", seconds,
           " s in a separate process (SFLSH_READ_PROBE_SECONDS sets the limit); nothing was read");
    }
    std::this_thread::sleep_for(pause);
    pause = std::min(2 * pause, std::chrono::microseconds(10000));
  }
  std::string how;
  if (WIFSIGNALED(status))
    how = strsignal(WTERMSIG(status));
  else if (!WIFEXITED(status))
    how = "status " + std::to_string(status);
  else if (WEXITSTATUS(status) != kProbeRead && WEXITSTATUS(status) != kProbeThrew)
    how = "exit code " + std::to_string(WEXITSTATUS(status)) + ", e.g. a sanitizer's report";  // ASan exits with 1
  if (!how.empty())
    fail(what, ": damaged file: parsing it crashed the reader library (", how, ") in a separate process; nothing was read");
}

}  // namespace sflsh::io
