#pragma once
// Signals that ask a run to write its checkpoint and stop (what Slurm's
// --signal and a time limit send): every iterative driver polls the flag and
// agrees on it across ranks before stopping.

namespace snl {

/// Installs the handlers for SIGTERM and SIGUSR1.
void install_stop_signal_handlers();
/// True once such a signal arrived on this process.
bool stop_signal_received();
/// Exit status of a run stopped by a signal after writing its checkpoint.
constexpr int kExitCheckpointed = 3;

}  // namespace snl
