#include "sflsh/io/crash_isolation.hpp"

#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "sflsh/core/error.hpp"

namespace sflsh::io {
namespace {
constexpr int kProbeRead = 0, kProbeThrew = 42;  // the child's exit codes
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
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return;
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
