#pragma once
// Worker processes for batch jobs (POSIX fork/exec, no shell): start a
// program with its output going to a log file, then wait for whichever
// finishes first and learn its exit status, wall time and peak memory.
#include <chrono>
#include <map>
#include <string>
#include <vector>

namespace sflsh {

/// How one child ended.
struct ChildExit {
  int pid = 0;
  int exit_code = -1;      ///< exit status, or -1 when killed by a signal
  int signal = 0;          ///< the signal that killed it, 0 if it exited
  double seconds = 0;      ///< wall time from start to exit
  double peak_rss_mib = 0; ///< the child's peak resident set size (getrusage ru_maxrss)
  /// "exit code 3", "killed by signal 9 (Killed)", "exit code 0".
  std::string describe() const;
};

class ChildProcesses {
 public:
  ChildProcesses() = default;
  ChildProcesses(const ChildProcesses&) = delete;
  ChildProcesses& operator=(const ChildProcesses&) = delete;
  /// Sends SIGTERM to and reaps every child still running.
  ~ChildProcesses();

  /// Starts `argv[0]` (a path; not looked up in PATH) with arguments `argv`.
  /// Its stdout and stderr go to `log_path` (truncated; "" = inherited).
  /// On Linux the child receives SIGTERM if this process dies first, so a
  /// killed batch leaves no orphan workers. Returns the pid; throws
  /// sflsh::Error if fork fails. An exec failure shows up as exit code 127
  /// with the reason in the log.
  int start(const std::vector<std::string>& argv, const std::string& log_path);
  /// Blocks until one of the started children ends. Throws if none runs.
  ChildExit wait_any();
  /// Children started and not yet waited for.
  int running() const { return int(started_.size()); }

 private:
  std::map<int, std::chrono::steady_clock::time_point> started_;
};

/// "<host>-<pid>": names temporary files that no other process, on this or
/// another machine sharing the folder, writes at the same time.
std::string process_tag();

/// Absolute path of the running executable (/proc/self/exe); throws if unknown.
std::string self_executable();

}  // namespace sflsh
