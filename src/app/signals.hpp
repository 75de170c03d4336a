#pragma once
// SIGTERM and SIGINT (a batch system's notice, a Ctrl-C) do not kill the run:
// the handler only records the signal; the time loop polls it every
// iteration, rolls the current step back, writes a checkpoint and ends with
// exit status 0. A second signal of the same kind kills at once.
namespace drape {

void install_stop_signals();
// The signal received since install_stop_signals() (0: none).
int stop_signal();
// "SIGTERM", "SIGINT" or "signal N".
const char* signal_name(int sig);

}  // namespace drape
