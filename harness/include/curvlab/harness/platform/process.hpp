// The running process and others, by id (DESIGN.md §9, "Platforms"): what
// staging names and the writer lock's holder slots need. POSIX in
// harness/src/platform/posix.cpp, Windows in windows.cpp. Thread-safe.
#pragma once

#include <cstdint>
#include <string>

namespace curvlab::harness::platform {

// This process's id.
std::int64_t process_id();

// True while a process with this id exists (one of another user counts as
// existing); false for ids <= 0.
bool process_alive(std::int64_t pid);

// The machine's host name, or "" when it cannot be had.
std::string host_name();

// Now, UTC, as 2026-01-31T12:00:00Z.
std::string utc_now_iso8601();

// Sets an environment variable unless it is set already.
void set_env_default(const char* name, const char* value);

}  // namespace curvlab::harness::platform
