#include "sflsh/core/child_processes.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "sflsh/core/error.hpp"

namespace sflsh {

std::string ChildExit::describe() const {
  if (signal != 0) return "killed by signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
  return "exit code " + std::to_string(exit_code);
}

ChildProcesses::~ChildProcesses() {
  for (const auto& [pid, start] : started_) kill(pid, SIGTERM);
  for (const auto& [pid, start] : started_) waitpid(pid, nullptr, 0);
}

int ChildProcesses::start(const std::vector<std::string>& argv, const std::string& log_path) {
  require(!argv.empty(), "ChildProcesses::start: empty command");
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t parent = getpid();
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) fail("cannot start a worker process (fork): ", std::strerror(errno));
  if (pid == 0) {
    // In the child: only async-signal-safe calls until exec.
#ifdef __linux__
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(126);  // the parent died before prctl
#endif
    if (!log_path.empty()) {
      const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) {
        dup2(fd, STDOUT_FILENO);
        dup2(fd, STDERR_FILENO);
        if (fd > STDERR_FILENO) close(fd);
      }
    }
    execv(args[0], args.data());
    const char* why = std::strerror(errno);
    const char* what = "cannot run worker: ";
    (void)!write(STDERR_FILENO, what, std::strlen(what));
    (void)!write(STDERR_FILENO, args[0], std::strlen(args[0]));
    (void)!write(STDERR_FILENO, ": ", 2);
    (void)!write(STDERR_FILENO, why, std::strlen(why));
    (void)!write(STDERR_FILENO, "\n", 1);
    _exit(127);
  }
  started_[pid] = std::chrono::steady_clock::now();
  return pid;
}

ChildExit ChildProcesses::wait_any() {
  require(!started_.empty(), "ChildProcesses::wait_any: no worker is running");
  while (true) {
    int status = 0;
    rusage usage{};
    const pid_t pid = wait4(-1, &status, 0, &usage);
    if (pid < 0) {
      if (errno == EINTR) continue;
      fail("waiting for worker processes failed: ", std::strerror(errno));
    }
    auto it = started_.find(pid);
    if (it == started_.end()) continue;  // not one of ours
    ChildExit e;
    e.pid = pid;
    e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - it->second).count();
    started_.erase(it);
    e.peak_rss_mib = double(usage.ru_maxrss) / 1024.0;  // KiB on Linux
    if (WIFEXITED(status)) {
      e.exit_code = WEXITSTATUS(status);
    } else if (WIFSIGNALED(status)) {
      e.signal = WTERMSIG(status);
    }
    return e;
  }
}

std::string process_tag() {
  char host[256] = {0};
  if (gethostname(host, sizeof(host) - 1) != 0 || !host[0]) std::strcpy(host, "host");
  return std::string(host) + "-" + std::to_string(getpid());
}

std::string self_executable() {
  std::error_code ec;
  const auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) fail("cannot find the running executable (/proc/self/exe): ", ec.message());
  return p.string();
}

}  // namespace sflsh
