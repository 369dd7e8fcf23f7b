#include "snl/core/stop_signal.hpp"

#include <csignal>
#include <cstring>

namespace snl {

namespace {
volatile std::sig_atomic_t g_stop_signal = 0;  // set by the handler only
extern "C" void on_stop_signal(int) { g_stop_signal = 1; }
}  // namespace

void install_stop_signal_handlers() {
  struct sigaction sa;
  std::memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGUSR1, &sa, nullptr);
}

bool stop_signal_received() { return g_stop_signal != 0; }

}  // namespace snl
