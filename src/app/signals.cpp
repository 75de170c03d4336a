#include "app/signals.hpp"

#include <csignal>
#include <cstdio>

namespace drape {

namespace {

volatile std::sig_atomic_t g_signal = 0;

extern "C" void on_stop_signal(int sig) {
  if (g_signal == sig) {  // asked twice: the user means it
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    return;
  }
  g_signal = sig;
}

}  // namespace

void install_stop_signals() {
  struct sigaction sa = {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
}

// Under a file-size limit (ulimit -f) the kernel sends SIGXFSZ to a process
// writing past it, and its default action kills the process at once: no
// message, a temporary file left behind, and on several ranks the others
// waiting in a collective. Ignored, the write returns EFBIG instead, and the
// run ends like on a full disk: exit 1, one message naming the file, the
// temporary removed and the previous checkpoint kept.
void ignore_file_size_signal() { std::signal(SIGXFSZ, SIG_IGN); }

int stop_signal() { return g_signal; }

const char* signal_name(int sig) {
  if (sig == SIGTERM) return "SIGTERM";
  if (sig == SIGINT) return "SIGINT";
  static char buf[32];
  std::snprintf(buf, sizeof buf, "signal %d", sig);
  return buf;
}

}  // namespace drape
