// Work in progress beside where it will land, named after the process that
// writes it: merge's OUT.merging-PID, a pooled export's
// $TMPDIR/curvlab-export-PID.sqlite, an export's DIR/bids.partial-PID. A
// process stopped by kill -9 or a power cut leaves its work behind (a pooled
// study can be hundreds of MB); the next run of the command removes what no
// living process owns. Thread-safe (no shared state).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <sys/types.h>

namespace curvlab::harness::data {

// True while a process with this id exists (another user's process counts
// as living; platform/process.hpp).
bool process_alive(pid_t pid);

// What a kind of work in progress is: a database (merge's OUT.merging-PID,
// a pooled export's copy), which may have SQLite's and curvlab's companions
// beside it; a plain file (a CSV export's part, a session's disk reserve);
// or a folder (a BIDS or Psych-DS export's part).
enum class StagingKind { database, file, folder };

// Removes the entries directly in `dir` named `prefix` + PID + rest, where
// PID is a process that no longer exists, rest is empty or, for a database,
// one of curvlab's own endings ([.sqlite][.merging-N] then nothing, -wal,
// -shm, -journal or .lock), and the entry is of `kind`: a regular file, or a
// folder (never through a link). Living processes'
// entries, other names and other kinds are left alone, as is anything that
// cannot be removed (no worse than before). Returns how many entries were
// removed.
std::size_t remove_stale_staging(const std::string& dir, const std::string& prefix, StagingKind kind);

// The same scan with another test of staleness: removes the entries named
// `prefix` + N + rest for which stale(N) is true (the session reserves of
// writer_lock.cpp, whose N is a session no live process holds).
std::size_t remove_numbered(const std::string& dir, const std::string& prefix, StagingKind kind,
                            const std::function<bool(std::int64_t number)>& stale);

}  // namespace curvlab::harness::data
