// What every curvlab TOML reader shares (the protocol loader, the HID
// mapping file): one guarded parse that never lets toml++ 3.3 reach its
// undefined behaviour, and field readers that look a key up and check its
// type and range. The readers report *what* is wrong; each file format words
// the message itself (the protocol collects every problem, the mapping file
// stops at the first), so their messages stay as users know them.
//
// Internal to curvlab_protocol and curvlab_devices (library curvlab_toml, a
// folder of its own below both): it exposes toml++ types, so it is not a
// public header. Thread-safe (no shared state).
#pragma once

#include <toml++/toml.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace curvlab::harness::toml_reader {

// A 1-based position in the text; line 0 when none is known.
struct Pos {
  int line = 0;
  int column = 0;
};

Pos pos_of(const toml::source_region& region);
Pos pos_of(const toml::node& node);

// "an integer", "a string", … for messages ("found a string").
std::string type_name(const toml::node& node);

// Text that cannot be read, and where.
struct SyntaxProblem {
  Pos pos;
  std::string message;
};

// The first place in `text` where toml++ 3.3 (Debian 12) would reach
// undefined behaviour, reported as a syntax problem; nullopt when the text is
// safe to parse. See toml_reader.cpp for the characters and places.
std::optional<SyntaxProblem> find_toml33_hazard(std::string_view text);

// The guarded parse every reader uses: the hazard scan, then toml++. `file`
// names the text in toml++'s source regions.
std::variant<toml::table, SyntaxProblem> parse(std::string_view text, const std::string& file);

// ---- field readers ------------------------------------------------------

enum class FieldStatus {
  absent,        // the key is not in the table
  ok,            // value holds what was written
  wrong_type,    // written, but not of the wanted type (node says what it is)
  out_of_range,  // an integer outside [lo, hi] (value holds it)
  not_finite,    // a float that is inf or nan
  empty,         // an empty string where one is required to say something
};

template <class T>
struct Field {
  FieldStatus status = FieldStatus::absent;
  T value{};
  const toml::node* node = nullptr;  // the value as written; null when absent
  [[nodiscard]] bool ok() const { return status == FieldStatus::ok; }
  [[nodiscard]] bool present() const { return status != FieldStatus::absent; }
};

Field<std::int64_t> read_integer(const toml::table& table, std::string_view key, std::int64_t lo,
                                 std::int64_t hi);
// An integer or a float, as a finite double.
Field<double> read_number(const toml::table& table, std::string_view key);
Field<std::string> read_string(const toml::table& table, std::string_view key, bool allow_empty = true);
Field<bool> read_bool(const toml::table& table, std::string_view key);
// A table of tables ([[name]]); wrong_type also for an empty array or one
// holding anything but tables.
Field<const toml::array*> read_array_of_tables(const toml::table& table, std::string_view key);

// The keys of `table` that are not in `allowed`, each with where it was
// written, in toml++'s table order (sorted by key).
struct UnknownKey {
  std::string key;
  Pos pos;
  const toml::node* node = nullptr;
};
std::vector<UnknownKey> unknown_keys(const toml::table& table, const std::vector<std::string>& allowed);

}  // namespace curvlab::harness::toml_reader
