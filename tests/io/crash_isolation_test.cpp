// probe_in_child_process: a probe that crashes becomes one error naming the file; one that
// throws or succeeds lets the caller go on; the fuzzers' opt-out skips the probe.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <string>
#include <thread>

#include "sflsh/core/error.hpp"
#include "sflsh/io/crash_isolation.hpp"

using namespace sflsh;

TEST(CrashIsolation, ACrashingProbeIsOneErrorNamingTheFile) {
  for (int sig : {SIGSEGV, SIGABRT}) {
    try {
      io::probe_in_child_process("damaged.h5", [sig] { std::raise(sig); });
      ADD_FAILURE() << "a probe killed by signal " << sig << " was accepted";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("damaged.h5: damaged file: parsing it crashed the reader library", 0), 0u) << what;
      EXPECT_NE(what.find("nothing was read"), std::string::npos) << what;
    }
  }
  // A sanitizer's report ends the process with exit code 1: a crash too.
  EXPECT_THROW(io::probe_in_child_process("x.h5", [] { std::_Exit(1); }), Error);
}

TEST(CrashIsolation, ProbesThatThrowOrSucceedReturn) {
  EXPECT_NO_THROW(io::probe_in_child_process("ok.h5", [] {}));
  EXPECT_NO_THROW(io::probe_in_child_process("bad.h5", [] { fail("bad.h5: dataset /x is missing"); }));
  // The probe runs in another process: what it changes stays there.
  int touched = 0;
  io::probe_in_child_process("ok.h5", [&] { touched = 1; });
  EXPECT_EQ(touched, 0);
}

TEST(CrashIsolation, AProbeThatHangsIsStoppedAtTheLimit) {
  setenv("SFLSH_READ_PROBE_SECONDS", "0.5", 1);
  const auto start = std::chrono::steady_clock::now();
  try {
    io::probe_in_child_process("loop.ply", [] {
      for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
    });
    ADD_FAILURE() << "a probe that never ends was accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("loop.ply: damaged file? parsing it did not finish within 0.5 s", 0), 0u) << what;
  }
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GE(waited, 0.5);
  EXPECT_LT(waited, 60.0) << "the child was not stopped";
  // A probe within the limit returns as before; a malformed limit falls back to the default.
  EXPECT_NO_THROW(io::probe_in_child_process("ok.h5", [] {}));
  setenv("SFLSH_READ_PROBE_SECONDS", "-3", 1);
  EXPECT_NO_THROW(io::probe_in_child_process("ok.h5", [] { std::this_thread::sleep_for(std::chrono::milliseconds(700)); }));
  unsetenv("SFLSH_READ_PROBE_SECONDS");
}

TEST(CrashIsolation, FuzzersOptOut) {
  setenv("SFLSH_READ_IN_PROCESS", "1", 1);
  EXPECT_NO_THROW(io::probe_in_child_process("x.h5", [] { std::raise(SIGSEGV); }));  // not run at all
  unsetenv("SFLSH_READ_IN_PROCESS");
  EXPECT_THROW(io::probe_in_child_process("x.h5", [] { std::raise(SIGSEGV); }), Error);
}
