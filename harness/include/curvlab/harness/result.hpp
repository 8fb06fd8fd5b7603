// The one result type of the harness (STYLE.md, "Three kinds of failure"):
// an expected failure — no runtime, no device, a bad protocol, a corrupt or
// foreign database, a full disk, a lost GPU — is a value the caller must
// handle, carrying a message a person can act on and a kind that decides the
// exit code. Broken contracts abort instead: value() on an error and error()
// on a value are bugs, not failures. An input checked as a whole (a
// protocol file) fails once with every problem found, each with its place.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace curvlab::harness {

// A 1-based position in a text file; line 0 means "no position known" (for
// example a problem with the file as a whole).
struct SourcePos {
  int line = 0;
  int column = 0;
};

// One problem at a place in an input file: the protocol loader reports
// every problem of a file this way, in one pass.
struct Diagnostic {
  std::string file;
  SourcePos pos;
  std::string field;    // dotted path, e.g. "blocks[2].timeline.iti_ms"
  std::string message;  // what was found and what was expected
};

// "file:line:column: error: field: message" (the position is left out when
// unknown, the field part when the problem is not tied to one field).
inline std::string format_diagnostic(const Diagnostic& d) {
  std::string out = d.file;
  // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on
  // `":" + std::to_string(…)`.
  if (d.pos.line > 0) {
    out += ':';
    out += std::to_string(d.pos.line);
    out += ':';
    out += std::to_string(d.pos.column);
  }
  out += ": error: ";
  if (!d.field.empty()) out += d.field + ": ";
  out += d.message;
  return out;
}

struct Error {
  enum class Kind {
    usage,         // bad arguments or options (exit 2)
    bad_input,     // a protocol, file or record that breaks its rules (exit 2)
    not_found,     // a file, session or trial that does not exist (exit 2)
    newer_schema,  // a data file written by a newer curvlab; refused rather than misread (exit 2)
    not_curvlab,   // some other SQLite file, or not SQLite at all (exit 2)
    corrupt,       // a damaged curvlab file (exit 2)
    in_use,        // a session or file a live process is writing (exit 2)
    io,            // cannot open, read or write a file (exit 1)
    read_only,     // the file or its folder is not writable (exit 1)
    disk_full,     // SQLITE_FULL, or too little free space to start (exit 1)
    busy,          // another process holds a lock for too long (exit 1)
    device,        // no GPU, headset, display or HID device; a runtime missing (exit 1)
    api,           // a Vulkan or OpenXR call failed while running (exit 1)
  };
  Kind kind = Kind::io;
  std::string message;  // names the file, call or field and what to do about it
  // Every located problem behind the failure, for a caller that lists them
  // (`curvlab validate` prints one line each); empty for other errors.
  std::vector<Diagnostic> diagnostics = {};
};

const char* to_string(Error::Kind kind);

// 2 for bad input (the person can fix the command or file), 1 for a
// run-time failure (README, "Command line").
inline int exit_code(const Error& e) {
  switch (e.kind) {
    case Error::Kind::usage:
    case Error::Kind::bad_input:
    case Error::Kind::not_found:
    case Error::Kind::newer_schema:
    case Error::Kind::not_curvlab:
    case Error::Kind::corrupt:
    case Error::Kind::in_use:
      return 2;
    default:
      return 1;
  }
}

struct Done {};

// A value or an Error.
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : state_(std::move(value)) {}      // NOLINT: implicit by design
  Result(Error error) : state_(std::move(error)) {}  // NOLINT: implicit by design

  bool has_value() const { return state_.index() == 0; }
  explicit operator bool() const { return has_value(); }

  T& value() & {
    check();
    return std::get<0>(state_);
  }
  const T& value() const& {
    check();
    return std::get<0>(state_);
  }
  T&& value() && {
    check();
    return std::get<0>(std::move(state_));
  }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

  const Error& error() const {
    if (has_value()) {
      std::fputs("curvlab::harness::Result::error() called on a value\n", stderr);
      std::abort();
    }
    return std::get<1>(state_);
  }

 private:
  void check() const {
    if (!has_value()) {
      std::fprintf(stderr, "curvlab::harness::Result::value() on an error: %s\n",
                   std::get<1>(state_).message.c_str());
      std::abort();
    }
  }
  std::variant<T, Error> state_;
};

inline const char* to_string(Error::Kind kind) {
  switch (kind) {
    case Error::Kind::usage: return "usage";
    case Error::Kind::bad_input: return "bad_input";
    case Error::Kind::not_found: return "not_found";
    case Error::Kind::newer_schema: return "newer_schema";
    case Error::Kind::in_use: return "in_use";
    case Error::Kind::not_curvlab: return "not_curvlab";
    case Error::Kind::corrupt: return "corrupt";
    case Error::Kind::io: return "io";
    case Error::Kind::read_only: return "read_only";
    case Error::Kind::disk_full: return "disk_full";
    case Error::Kind::busy: return "busy";
    case Error::Kind::device: return "device";
    case Error::Kind::api: return "api";
  }
  return "unknown";
}

}  // namespace curvlab::harness
