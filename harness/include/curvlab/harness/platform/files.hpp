// File-system questions and moves whose answers differ by platform
// (DESIGN.md §9): writability, free space, replacing a path in one step.
// POSIX in harness/src/platform/posix.cpp, Windows in windows.cpp.
// Thread-safe (no shared state).
#pragma once

#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>

namespace curvlab::harness::platform {

// True when this process may write `path` (a file, or a folder to create
// files in).
bool writable(const std::string& path);

// Bytes free to this user on the file system holding `dir`; nullopt when
// that cannot be known.
std::optional<std::uint64_t> free_bytes(const std::string& dir);

// Moves `from` onto `to` in one step, replacing a file there, or a folder
// that is missing or empty. 0 on success, else an errno value (ENOTEMPTY or
// EEXIST: `to` is a folder with content).
int rename_replacing(const std::string& from, const std::string& to);

// Exchanges two paths in one step; 0 on success, else an errno value
// (EINVAL or ENOSYS where the file system or platform cannot).
int exchange_paths(const std::string& a, const std::string& b);

// Creates `path` for writing (binary) only if it does not exist yet, in one
// step (O_EXCL); nullptr when it exists or cannot be made.
std::FILE* create_new_file(const std::string& path);

// `relative` resolved against the folder of the running executable (UTF-8).
std::string beside_executable(const std::string& relative);

}  // namespace curvlab::harness::platform
