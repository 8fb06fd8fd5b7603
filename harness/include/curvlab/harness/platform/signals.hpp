// Asking a running session to stop from outside (DESIGN.md §9): Ctrl-C, a
// terminal closed, a service manager's stop. POSIX: SIGINT, SIGTERM and
// SIGHUP through sigaction; Windows: SIGINT and SIGTERM through the C
// runtime plus the console's close, logoff and shutdown events (reported as
// SIGHUP's number, 1, which the C runtime lacks). The handler only stores
// the signal's number; the frame loop polls it.
#pragma once

#include <atomic>
#include <string>

namespace curvlab::harness::platform {

// Installs the handlers once (each fires once, then the default action
// returns: a second Ctrl-C ends the process). Returns the number of the
// first signal received, 0 until then.
const std::atomic<int>& catch_stop_signals();

// The number of the first signal received, 0 until then (installs nothing).
int stop_signal_received();

// "Interrupt", "Terminated", "Hangup", ...
std::string signal_name(int sig);

}  // namespace curvlab::harness::platform
