#include "sflsh/core/interrupt.hpp"

#include <csignal>

namespace sflsh {
namespace {

volatile std::sig_atomic_t g_signal = 0;

extern "C" void on_signal(int sig) {
  g_signal = sig;
  std::signal(sig, SIG_DFL);  // a second Ctrl-C ends the process at once
}

using Handler = void (*)(int);
Handler g_prev_int = SIG_DFL, g_prev_term = SIG_DFL;

const char* signal_name(int sig) {
  switch (sig) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    default: return "a signal";
  }
}

}  // namespace

InterruptScope::InterruptScope() {
  g_signal = 0;
  g_prev_int = std::signal(SIGINT, on_signal);
  g_prev_term = std::signal(SIGTERM, on_signal);
}

InterruptScope::~InterruptScope() {
  std::signal(SIGINT, g_prev_int == SIG_ERR ? SIG_DFL : g_prev_int);
  std::signal(SIGTERM, g_prev_term == SIG_ERR ? SIG_DFL : g_prev_term);
}

int interrupt_signal() { return g_signal; }
void reset_interrupt() { g_signal = 0; }
void request_interrupt(int signal) { g_signal = signal; }

void throw_if_interrupted(const std::string& where) {
  const int sig = g_signal;
  if (sig == 0) return;
  throw Interrupted(std::string("interrupted by ") + signal_name(sig) + (where.empty() ? "" : " " + where), sig);
}

}  // namespace sflsh
