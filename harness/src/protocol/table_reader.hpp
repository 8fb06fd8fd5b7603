// The protocol loader's field readers: each looks a key up, checks what was
// written and, when it is wrong, adds a diagnostic with the file, position,
// dotted field and what was expected, then goes on, so that an author sees
// every problem in one pass. The loader reads the protocol's sections with
// them, and each judgement type reads its own table with them
// (judgements/judgement_format.hpp).
//
// Internal to curvlab_protocol: it exposes toml++ types. Not thread-safe: one
// reader per load.
#pragma once

#include "curvlab/harness/protocol/diagnostic.hpp"
#include "curvlab/harness/protocol/settings.hpp"
#include "toml_reader.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::protocol {

SourcePos pos_of(const toml::source_region& r);
SourcePos pos_of(const toml::node& n);
SourcePos to_source_pos(toml_reader::Pos p);

// "prefix.key", or "key" at the top level.
std::string join(const std::string& prefix, std::string_view key);
// A number as the protocol would write it, in shortest form: 0.05, -1, 1e-06.
std::string number_label(double v);
// "[lo, hi]" with number_label's numbers.
std::string interval_label(double lo, double hi);
// "\"a\", \"b\", \"c\"".
std::string quoted_list(const std::vector<std::string>& items);
// A lower-case identifier: a-z or _ first, then a-z, 0-9, _ and -; at most 64.
bool is_identifier(const std::string& s);
// The key and button names an answer may be bound to.
const std::vector<std::string>& key_names();
const std::vector<std::string>& button_names();

class TableReader {
 public:
  explicit TableReader(std::string file) : file_(std::move(file)) {}

  // The file the diagnostics name.
  [[nodiscard]] const std::string& file() const { return file_; }
  void error(SourcePos pos, std::string field, std::string message);
  [[nodiscard]] bool failed() const { return !diags_.empty(); }
  std::vector<Diagnostic> take_diagnostics() { return std::move(diags_); }

  // Reports every key of `t` not in `allowed`, with a did-you-mean.
  void check_keys(const toml::table& t, const std::string& prefix, const std::vector<std::string>& allowed);
  const toml::table* sub_table(const toml::table& t, std::string_view key, const std::string& prefix);
  std::optional<std::string> get_string(const toml::table& t, std::string_view key, const std::string& prefix,
                                        bool required);
  std::optional<std::int64_t> get_int(const toml::table& t, std::string_view key, const std::string& prefix,
                                      std::int64_t lo, std::int64_t hi, bool required);
  std::optional<double> get_number(const toml::table& t, std::string_view key, const std::string& prefix,
                                   bool required);
  std::optional<bool> get_bool(const toml::table& t, std::string_view key, const std::string& prefix);
  std::optional<std::string> get_enum(const toml::table& t, std::string_view key, const std::string& prefix,
                                      const std::vector<std::string>& allowed);
  // With `allowed`, each element must be one of those names (keys, buttons).
  std::vector<std::string> get_string_array(const toml::table& t, std::string_view key, const std::string& prefix,
                                            const std::vector<std::string>* allowed = nullptr);

  // An integer or float node as a double.
  static std::optional<double> node_number(const toml::node& n);
  // A scalar node as a setting value.
  static std::optional<SettingValue> to_value(const toml::node& n);
  // Adds what was actually written when the registry's message does not say.
  static std::string with_found(const std::string& message, const toml::node& n);

 private:
  std::string file_;
  std::vector<Diagnostic> diags_;
};

}  // namespace curvlab::harness::protocol
