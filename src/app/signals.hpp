#pragma once
// SIGTERM and SIGINT (a batch system's notice, a Ctrl-C) do not kill the run:
// the handler only records the signal; the time loop polls it every
// iteration, rolls the current step back, writes a checkpoint and ends with
// exit status 0. A second signal of the same kind kills at once.
namespace drape {

void install_stop_signals();
// SIGXFSZ ignored (see signals.cpp): a write past a file-size limit fails
// with EFBIG, which the writers report, instead of killing the run.
void ignore_file_size_signal();
// The signal received since install_stop_signals() (0: none).
int stop_signal();
// "SIGTERM", "SIGINT" or "signal N".
const char* signal_name(int sig);

}  // namespace drape
