// The guarded TOML parse and the field readers shared by every curvlab TOML
// reader (toml_reader.hpp).
#include "toml_reader.hpp"

#include "curvlab/harness/utf8.hpp"

#include <cmath>

namespace curvlab::harness::toml_reader {
namespace {

// toml++ 3.3 (Debian 12) reaches __builtin_unreachable() — undefined
// behaviour, found by our fuzzer and known upstream (marzer/tomlplusplus#190,
// #295, fixed after 3.3) — when it asks whether certain non-ASCII code points
// are whitespace: U+00A1–U+0499, U+2D8E–U+3187 and U+FB46–U+FEFE (except
// U+3000). It asks for characters outside strings, inside keys (quoted keys
// are recorded character by character) and after a line-ending backslash in a
// multi-line basic string. Value strings and comments are safe, so
// instructions may be written in any language. This scan finds the unsafe
// places first and reports them as syntax errors instead of calling the parser.
bool unsafe_for_toml33(char32_t c) {
  if (c < 0xA1 || c > 0xFEFF || c == 0x3000 || c == 0xFEFF) return false;
  const auto child = (static_cast<std::uint64_t>(c) - 0xA0u) / 0x3FAu;
  return child == 0 || child == 11 || child == 63;
}

std::string hex4(char32_t c) {
  static const char* digits = "0123456789ABCDEF";
  std::string out;
  for (int shift = c > 0xFFFF ? 20 : 12; shift >= 0; shift -= 4) out += digits[(c >> shift) & 0xFu];
  return out;
}

bool is_toml_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

// Walks the text code point by code point, keeping the line and column.
class Scanner {
 public:
  explicit Scanner(std::string_view text) : text_(text) {}

  [[nodiscard]] bool at_end() const { return i_ >= text_.size(); }
  [[nodiscard]] char peek() const { return text_[i_]; }
  [[nodiscard]] Pos here() const { return Pos{line_, column_}; }
  [[nodiscard]] bool starts(std::string_view s) const { return text_.substr(i_, s.size()) == s; }

  // Decodes the code point here (invalid UTF-8: the byte itself; toml++
  // reports those cleanly) and moves past it.
  char32_t next() {
    const auto b0 = static_cast<unsigned char>(text_[i_]);
    std::size_t len = b0 < 0x80 ? 1 : (b0 >> 5) == 6 ? 2 : (b0 >> 4) == 14 ? 3 : (b0 >> 3) == 30 ? 4 : 1;
    if (i_ + len > text_.size()) len = 1;
    char32_t c = len == 1 ? b0 : len == 2 ? (b0 & 0x1Fu) : len == 3 ? (b0 & 0x0Fu) : (b0 & 0x07u);
    for (std::size_t k = 1; k < len; ++k) {
      const auto b = static_cast<unsigned char>(text_[i_ + k]);
      if ((b >> 6) != 2) {
        len = 1;
        c = b0;
        break;
      }
      c = (c << 6) | (b & 0x3Fu);
    }
    i_ += len;
    if (c == U'\n') {
      ++line_;
      column_ = 1;
    } else {
      ++column_;
    }
    return c;
  }

  void skip(int code_points) {
    for (int k = 0; k < code_points; ++k) next();
  }

  void skip_comment() {
    while (!at_end() && peek() != '\n') next();
  }

 private:
  std::string_view text_;
  std::size_t i_ = 0;
  int line_ = 1;
  int column_ = 1;
};

// Whether a key or a value comes next, from the structure seen outside
// strings and comments.
struct KeyTracker {
  std::vector<char> nest;  // '[' array, '{' inline table (value side only)
  bool key_position = true;

  void see(char32_t c) {
    switch (c) {
      case U'=': key_position = false; break;
      case U'\n': if (nest.empty()) key_position = true; break;
      case U'[': if (!(key_position && nest.empty())) nest.push_back('['); break;
      case U']': if (!nest.empty() && nest.back() == '[') nest.pop_back(); break;
      case U'{': nest.push_back('{'); key_position = true; break;
      case U'}': if (!nest.empty()) nest.pop_back(); key_position = false; break;
      case U',': if (!nest.empty() && nest.back() == '{') key_position = true; break;
      default: break;
    }
  }
};

// A quote glued to a bare value (`0"x"`) is a syntax error, but toml++
// first scans the whole run of characters as one value — into the
// "string" — classifying each, so report it here.
std::optional<SyntaxProblem> glued_quote(char prev, Pos at) {
  if (std::string_view(" \t\r\n=[{,.").find(prev) != std::string_view::npos) return std::nullopt;
  return SyntaxProblem{at, std::string("unexpected quote right after '") + prev +
                               "': expected whitespace, '=', '[', '{', ',' or '.' before a string"};
}

// After a line-ending backslash in a multi-line basic string: the
// whitespace it trims, then the first character after it.
std::optional<SyntaxProblem> scan_line_continuation(Scanner& s) {
  while (!s.at_end() && is_toml_space(s.peek())) s.next();
  const Pos after = s.here();
  if (s.at_end() || static_cast<unsigned char>(s.peek()) < 0x80) return std::nullopt;
  const char32_t c = s.next();
  if (!unsafe_for_toml33(c)) return std::nullopt;
  return SyntaxProblem{after, "U+" + hex4(c) +
                                  " right after a line-ending backslash cannot be read by the TOML "
                                  "library (toml++ 3.3); write it as the escape \\u" + hex4(c)};
}

// A string from its opening quote to past its closing delimiter.
std::optional<SyntaxProblem> scan_string(Scanner& s, bool is_key) {
  const char quote = s.peek();
  const std::string_view delim = quote == '"' ? std::string_view("\"\"\"") : std::string_view("'''");
  const bool triple = s.starts(delim);
  const bool basic = quote == '"';
  s.skip(triple ? 3 : 1);
  while (!s.at_end()) {
    if (triple ? s.starts(delim) : s.peek() == quote) {
      s.skip(triple ? 3 : 1);
      // A closing delimiter may be followed by up to two more quotes.
      while (triple && !s.at_end() && s.peek() == quote) s.next();
      return std::nullopt;
    }
    if (!triple && s.peek() == '\n') return std::nullopt;  // unterminated: toml++ reports it
    const Pos cp_at = s.here();
    if (basic && s.peek() == '\\') {
      s.next();
      if (s.at_end()) return std::nullopt;
      if (triple && is_toml_space(s.peek())) {
        if (auto problem = scan_line_continuation(s)) return problem;
        continue;
      }
      s.next();  // the escaped character
      continue;
    }
    const char32_t c = s.next();
    if (is_key && c >= 0x80)
      return SyntaxProblem{cp_at, "non-ASCII character U+" + hex4(c) + " in a key: keys are ASCII names"};
  }
  return std::nullopt;
}

}  // namespace

std::optional<SyntaxProblem> find_toml33_hazard(std::string_view text) {
  Scanner s(text);
  KeyTracker keys;
  char prev = '\n';  // the last character outside strings and comments
  while (!s.at_end()) {
    const Pos at = s.here();
    const char ch = s.peek();
    if (ch == '#') {
      s.skip_comment();
      prev = ' ';
      continue;
    }
    if (ch == '"' || ch == '\'') {
      if (auto problem = glued_quote(prev, at)) return problem;
      prev = ch;
      if (auto problem = scan_string(s, keys.key_position)) return problem;
      continue;
    }
    const char32_t c = s.next();
    prev = static_cast<char>(c);
    if (c >= 0x80)
      return SyntaxProblem{at, "non-ASCII character U+" + hex4(c) +
                            " outside a string or comment (TOML allows it only inside quotes or after #)"};
    keys.see(c);
  }
  return std::nullopt;
}


Pos pos_of(const toml::source_region& region) {
  return {static_cast<int>(region.begin.line), static_cast<int>(region.begin.column)};
}
Pos pos_of(const toml::node& node) { return pos_of(node.source()); }

std::string type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a float";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::date: return "a date";
    case toml::node_type::time: return "a time";
    case toml::node_type::date_time: return "a date-time";
    default: return "nothing";
  }
}

std::variant<toml::table, SyntaxProblem> parse(std::string_view text, const std::string& file) {
  // toml++ refuses bytes that are not UTF-8 too ("Encountered invalid utf-8
  // sequence", a column early); this names the byte and what to do about it,
  // as every other text file's reader does (curvlab/harness/utf8.hpp).
  if (const auto fault = find_invalid_utf8(text))
    return SyntaxProblem{{static_cast<int>(fault->line), static_cast<int>(fault->column)}, utf8_fault_text(*fault)};
  if (auto hazard = find_toml33_hazard(text)) return *std::move(hazard);
  try {
    return toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    return SyntaxProblem{pos_of(e.source()), std::string(e.description())};
  }
}

Field<std::int64_t> read_integer(const toml::table& table, std::string_view key, std::int64_t lo,
                                 std::int64_t hi) {
  Field<std::int64_t> f;
  f.node = table.get(key);
  if (f.node == nullptr) return f;
  const auto* i = f.node->as_integer();
  if (i == nullptr) {
    f.status = FieldStatus::wrong_type;
    return f;
  }
  f.value = i->get();
  f.status = f.value < lo || f.value > hi ? FieldStatus::out_of_range : FieldStatus::ok;
  return f;
}

Field<double> read_number(const toml::table& table, std::string_view key) {
  Field<double> f;
  f.node = table.get(key);
  if (f.node == nullptr) return f;
  if (const auto* i = f.node->as_integer()) {
    f.value = static_cast<double>(i->get());
  } else if (const auto* d = f.node->as_floating_point()) {
    f.value = d->get();
  } else {
    f.status = FieldStatus::wrong_type;
    return f;
  }
  f.status = std::isfinite(f.value) ? FieldStatus::ok : FieldStatus::not_finite;
  return f;
}

Field<std::string> read_string(const toml::table& table, std::string_view key, bool allow_empty) {
  Field<std::string> f;
  f.node = table.get(key);
  if (f.node == nullptr) return f;
  const auto* s = f.node->as_string();
  if (s == nullptr) {
    f.status = FieldStatus::wrong_type;
    return f;
  }
  f.value = s->get();
  f.status = f.value.empty() && !allow_empty ? FieldStatus::empty : FieldStatus::ok;
  return f;
}

Field<bool> read_bool(const toml::table& table, std::string_view key) {
  Field<bool> f;
  f.node = table.get(key);
  if (f.node == nullptr) return f;
  const auto* b = f.node->as_boolean();
  if (b == nullptr) {
    f.status = FieldStatus::wrong_type;
    return f;
  }
  f.value = b->get();
  f.status = FieldStatus::ok;
  return f;
}

Field<const toml::array*> read_array_of_tables(const toml::table& table, std::string_view key) {
  Field<const toml::array*> f;
  f.node = table.get(key);
  if (f.node == nullptr) return f;
  const auto* array = f.node->as_array();
  if (array == nullptr || !array->is_array_of_tables() || array->empty()) {
    f.status = FieldStatus::wrong_type;
    return f;
  }
  f.value = array;
  f.status = FieldStatus::ok;
  return f;
}

std::vector<UnknownKey> unknown_keys(const toml::table& table, const std::vector<std::string>& allowed) {
  std::vector<UnknownKey> out;
  for (const auto& [k, v] : table) {
    const std::string key(k.str());
    bool known = false;
    for (const auto& a : allowed) known = known || a == key;
    if (!known) out.push_back({key, pos_of(k.source()), &v});
  }
  return out;
}

}  // namespace curvlab::harness::toml_reader
