// Worker processes: exit codes, signals, exec failures, logs, timing, memory.
#include "sflsh/core/child_processes.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>

#include "test_support.hpp"

using namespace sflsh;

namespace {
std::string read_all(const std::string& path) {
  std::ifstream f(path);
  return std::string(std::istreambuf_iterator<char>(f), {});
}
}  // namespace

TEST(ChildProcesses, ReportsExitCodesSignalsExecFailuresAndLogs) {
  test::TempDir dir;
  ChildProcesses pool;
  const int a = pool.start({"/bin/sh", "-c", "echo out; echo err >&2; exit 3"}, dir.file("a.log"));
  const int b = pool.start({"/bin/sh", "-c", "kill -9 $$"}, dir.file("b.log"));
  const int c = pool.start({dir.file("no-such-program")}, dir.file("c.log"));
  const int d = pool.start({"/bin/sh", "-c", "sleep 0.3"}, "");
  EXPECT_EQ(pool.running(), 4);
  std::set<int> seen;
  for (int i = 0; i < 4; ++i) {
    const ChildExit e = pool.wait_any();
    seen.insert(e.pid);
    if (e.pid == a) {
      EXPECT_EQ(e.exit_code, 3);
      EXPECT_EQ(e.signal, 0);
      EXPECT_EQ(e.describe(), "exit code 3");
      EXPECT_GT(e.peak_rss_mib, 0.1) << "the kernel's peak RSS of the child";
    } else if (e.pid == b) {
      EXPECT_EQ(e.signal, 9);
      EXPECT_EQ(e.exit_code, -1);
      EXPECT_NE(e.describe().find("killed by signal 9"), std::string::npos) << e.describe();
    } else if (e.pid == c) {
      EXPECT_EQ(e.exit_code, 127);
    } else if (e.pid == d) {
      EXPECT_EQ(e.exit_code, 0);
      EXPECT_GE(e.seconds, 0.3);
      EXPECT_LT(e.seconds, 30.0);
    }
  }
  EXPECT_EQ(seen, (std::set<int>{a, b, c, d}));
  EXPECT_EQ(pool.running(), 0);
  EXPECT_EQ(read_all(dir.file("a.log")), "out\nerr\n");
  EXPECT_NE(read_all(dir.file("c.log")).find("cannot run worker: " + dir.file("no-such-program")), std::string::npos);
  test::expect_error([&] { pool.wait_any(); }, {"no worker is running"});
}

TEST(ChildProcesses, DestructorStopsRunningChildren) {
  test::TempDir dir;
  int pid = 0;
  {
    ChildProcesses pool;
    pid = pool.start({"/bin/sh", "-c", "sleep 30"}, "");
  }
  EXPECT_NE(kill(pid, 0), 0) << "the child was terminated and reaped";
}

TEST(ChildProcesses, TagAndExecutable) {
  const std::string tag = process_tag();
  EXPECT_EQ(tag.substr(tag.rfind('-') + 1), std::to_string(getpid()));
  EXPECT_GT(tag.rfind('-'), 0u) << "host name before the pid: " << tag;
  EXPECT_TRUE(std::filesystem::exists(self_executable()));
  EXPECT_EQ(std::filesystem::path(self_executable()).filename(), "test_core");
}
