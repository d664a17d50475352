#pragma once
// Cooperative interruption by SIGINT/SIGTERM. A command that streams output
// (`sflsh simulate`) holds an InterruptScope: the first signal only sets a
// flag (and restores the default action, so a second one kills at once); long
// loops call throw_if_interrupted() between steps, which throws Interrupted so
// that the stack unwinds and every partial output file is removed by its
// owner's destructor. Outside a scope the signals keep their default action.
#include <string>

#include "sflsh/core/error.hpp"

namespace sflsh {

/// Thrown by throw_if_interrupted(); signal() is the signal number received.
class Interrupted : public Error {
 public:
  Interrupted(const std::string& what, int signal) : Error(what), signal_(signal) {}
  int signal() const { return signal_; }
  /// The shell's exit code for death by this signal: 128 + signal (130 for SIGINT).
  int exit_code() const { return 128 + signal_; }

 private:
  int signal_;
};

/// Installs flag-setting handlers for SIGINT and SIGTERM for its lifetime and
/// restores the previous handlers on destruction. Not nestable.
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
};

/// The signal received since the last reset (0: none).
int interrupt_signal();
/// Forgets a received signal (tests; an InterruptScope also resets on entry).
void reset_interrupt();
/// Records `signal` as if it had been received (tests; async-signal-safe).
void request_interrupt(int signal);
/// Throws Interrupted("interrupted by SIGINT <where>") when a signal was received.
void throw_if_interrupted(const std::string& where = "");

}  // namespace sflsh
