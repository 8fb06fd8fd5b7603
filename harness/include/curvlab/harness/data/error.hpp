// Expected failures of the data layer (disk full, read-only file, a file from
// a newer curvlab…) as values the caller must handle (STYLE.md, "Three kinds
// of failure"). Broken contracts abort instead.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <variant>

namespace curvlab::data {

struct DataError {
  enum class Kind {
    io,            // cannot open, read or write the file
    read_only,     // the file or its folder is not writable
    disk_full,     // SQLITE_FULL or too little free space to start a session
    newer_schema,  // written by a newer curvlab; refused rather than misread
    not_curvlab,   // some other SQLite file
    corrupt,       // integrity check failed or not a database
    busy,          // another process holds the write lock for too long
    bad_input,     // a record that violates the schema (caller's data)
    not_found,     // a session / trial id that does not exist
  };
  Kind kind = Kind::io;
  std::string message;  // names the file and what to do about it
};

const char* to_string(DataError::Kind kind);

struct Done {};

// A value or a DataError. value() on an error is a broken contract: it aborts
// with the error's message rather than throwing.
template <class T>
class [[nodiscard]] Expected {
 public:
  Expected(T value) : state_(std::move(value)) {}          // NOLINT: implicit by design
  Expected(DataError error) : state_(std::move(error)) {}  // NOLINT: implicit by design

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
  const DataError& error() const {
    if (has_value()) {
      std::fputs("curvlab::data::Expected::error() called on a value\n", stderr);
      std::abort();
    }
    return std::get<1>(state_);
  }

 private:
  void check() const {
    if (!has_value()) {
      std::fprintf(stderr, "curvlab::data::Expected::value() on an error: %s\n",
                   std::get<1>(state_).message.c_str());
      std::abort();
    }
  }
  std::variant<T, DataError> state_;
};

}  // namespace curvlab::data
