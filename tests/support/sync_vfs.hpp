// An SQLite VFS shim for tests and benchmarks: it forwards every call to the
// platform's default VFS and, on each xSync (the call that waits for the
// disk), records which thread asked and can add a delay that stands in for
// a slow disk (a lab PC's spinning disk or a network share).
//
// install() registers it as the default VFS of the process, so every
// connection opened afterwards — the session's and the SampleWriter's —
// goes through it. Not for the shipped program: only tests and benchmarks
// link it.
//
// Thread-safety: the counters are guarded by a mutex; set_sync_delay() and
// reset() may be called from any thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <thread>

namespace curvlab::testing::sync_vfs {

// Registers the shim as the default VFS (idempotent).
void install();
// Time each xSync waits before it returns (zero by default).
void set_sync_delay(std::chrono::microseconds delay);
// xSync calls per thread since the last reset().
std::map<std::thread::id, std::int64_t> syncs_by_thread();
std::int64_t syncs_from(std::thread::id thread);
std::int64_t total_syncs();
void reset();

}  // namespace curvlab::testing::sync_vfs
