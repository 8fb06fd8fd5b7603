#include "table_reader.hpp"

#include <algorithm>
#include <cctype>

namespace curvlab::harness::protocol {

namespace tr = toml_reader;
using tr::type_name;

SourcePos to_source_pos(tr::Pos p) { return {p.line, p.column}; }
SourcePos pos_of(const toml::source_region& r) { return to_source_pos(tr::pos_of(r)); }
SourcePos pos_of(const toml::node& n) { return to_source_pos(tr::pos_of(n)); }

std::string join(const std::string& prefix, std::string_view key) {
  return prefix.empty() ? std::string(key) : prefix + "." + std::string(key);
}

std::string number_label(double v) { return value_label(SettingValue(std::in_place_type<double>, v)); }

std::string interval_label(double lo, double hi) {
  // Appends, not operator+ on a literal: GCC 12 warns falsely (-Wrestrict).
  std::string out = "[";
  out.append(number_label(lo)).append(", ").append(number_label(hi)).append("]");
  return out;
}

std::string quoted_list(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? ", \"" : "\"") + items[i] + "\"";
  return out;
}

bool is_identifier(const std::string& s) {
  if (s.empty() || s.size() > 64) return false;
  if (!(std::islower(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return std::islower(static_cast<unsigned char>(c)) || std::isdigit(static_cast<unsigned char>(c)) ||
           c == '_' || c == '-';
  });
}

const std::vector<std::string>& key_names() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> k;
    for (char c = 'a'; c <= 'z'; ++c) k.emplace_back(1, c);
    for (char c = '0'; c <= '9'; ++c) k.emplace_back(1, c);
    for (const char* n : {"left", "right", "up", "down", "space", "enter", "tab", "backspace",
                          "comma", "period", "slash", "semicolon", "shift", "control"})
      k.emplace_back(n);
    return k;  // "escape" is reserved: it pauses the session
  }();
  return keys;
}

const std::vector<std::string>& button_names() {
  static const std::vector<std::string> buttons = [] {
    std::vector<std::string> b{"a", "b", "x", "y", "left_trigger", "right_trigger", "left_grip",
                               "right_grip"};
    for (const char* hand : {"left", "right"})
      for (const char* dir : {"left", "right", "up", "down", "click"})
        b.push_back(std::string(hand) + "_thumbstick_" + dir);
    for (int i = 1; i <= 32; ++i) b.push_back("hid_" + std::to_string(i));
    return b;
  }();
  return buttons;
}

void TableReader::error(SourcePos pos, std::string field, std::string message) {
  diags_.push_back({file_, pos, std::move(field), std::move(message)});
}

void TableReader::check_keys(const toml::table& t, const std::string& prefix,
                             const std::vector<std::string>& allowed) {
  for (const auto& unknown : tr::unknown_keys(t, allowed)) {
    std::string msg = "unknown key \"" + unknown.key + "\"";
    const std::string guess = closest_match(unknown.key, allowed);
    if (!guess.empty()) msg += "; did you mean \"" + guess + "\"?";
    msg += " Expected one of: " + quoted_list(allowed);
    error(to_source_pos(unknown.pos), join(prefix, unknown.key), msg);
  }
}

const toml::table* TableReader::sub_table(const toml::table& t, std::string_view key, const std::string& prefix) {
  const toml::node* n = t.get(key);
  if (!n) return nullptr;
  if (const auto* tt = n->as_table()) return tt;
  error(pos_of(*n), join(prefix, key), "expected a table, found " + type_name(*n));
  return nullptr;
}

std::optional<std::string> TableReader::get_string(const toml::table& t, std::string_view key,
                                                   const std::string& prefix, bool required) {
  const auto f = tr::read_string(t, key);
  if (f.ok()) return f.value;
  if (f.present()) error(pos_of(*f.node), join(prefix, key), "expected a string, found " + type_name(*f.node));
  else if (required) error(pos_of(t), join(prefix, key), "missing required string");
  return std::nullopt;
}

std::optional<std::int64_t> TableReader::get_int(const toml::table& t, std::string_view key,
                                                 const std::string& prefix, std::int64_t lo, std::int64_t hi,
                                                 bool required) {
  const auto f = tr::read_integer(t, key, lo, hi);
  // Appends, not operator+ on a literal: GCC 12 warns falsely (-Wrestrict).
  std::string range = "[";
  range.append(std::to_string(lo)).append(", ").append(std::to_string(hi)).append("]");
  switch (f.status) {
    case tr::FieldStatus::ok: return f.value;
    case tr::FieldStatus::absent:
      if (required) error(pos_of(t), join(prefix, key), "missing required integer in " + range);
      break;
    case tr::FieldStatus::out_of_range:
      error(pos_of(*f.node), join(prefix, key),
            "expected an integer in " + range + ", found " + std::to_string(f.value));
      break;
    default:
      error(pos_of(*f.node), join(prefix, key), "expected an integer in " + range + ", found " + type_name(*f.node));
      break;
  }
  return std::nullopt;
}

std::optional<double> TableReader::node_number(const toml::node& n) {
  if (const auto* i = n.as_integer()) return static_cast<double>(i->get());
  if (const auto* f = n.as_floating_point()) return f->get();
  return std::nullopt;
}

std::optional<double> TableReader::get_number(const toml::table& t, std::string_view key,
                                              const std::string& prefix, bool required) {
  const auto f = tr::read_number(t, key);
  if (f.ok()) return f.value;
  if (!f.present()) {
    if (required) error(pos_of(t), join(prefix, key), "missing required number");
    return std::nullopt;
  }
  error(pos_of(*f.node), join(prefix, key),
        "expected a finite number, found " +
            (f.status == tr::FieldStatus::not_finite ? std::string("a non-finite float") : type_name(*f.node)));
  return std::nullopt;
}

std::optional<bool> TableReader::get_bool(const toml::table& t, std::string_view key, const std::string& prefix) {
  const auto f = tr::read_bool(t, key);
  if (f.status == tr::FieldStatus::wrong_type)
    error(pos_of(*f.node), join(prefix, key), "expected true or false, found " + type_name(*f.node));
  if (!f.ok()) return std::nullopt;
  return f.value;
}

std::optional<std::string> TableReader::get_enum(const toml::table& t, std::string_view key,
                                                 const std::string& prefix, const std::vector<std::string>& allowed) {
  const toml::node* n = t.get(key);
  if (!n) return std::nullopt;
  const auto* s = n->as_string();
  if (!s) {
    error(pos_of(*n), join(prefix, key), "expected one of " + quoted_list(allowed) + ", found " + type_name(*n));
    return std::nullopt;
  }
  if (std::find(allowed.begin(), allowed.end(), s->get()) != allowed.end()) return s->get();
  error(pos_of(*n), join(prefix, key), unknown_value(s->get(), allowed));
  return std::nullopt;
}

std::vector<std::string> TableReader::get_string_array(const toml::table& t, std::string_view key,
                                                       const std::string& prefix,
                                                       const std::vector<std::string>* allowed) {
  std::vector<std::string> out;
  const toml::node* n = t.get(key);
  if (!n) return out;
  const auto* arr = n->as_array();
  if (!arr) {
    error(pos_of(*n), join(prefix, key), "expected an array of strings, found " + type_name(*n));
    return out;
  }
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const toml::node& e = (*arr)[i];
    const std::string field = join(prefix, key) + "[" + std::to_string(i + 1) + "]";
    const auto* s = e.as_string();
    if (!s) {
      error(pos_of(e), field, "expected a string, found " + type_name(e));
      continue;
    }
    if (allowed && std::find(allowed->begin(), allowed->end(), s->get()) == allowed->end()) {
      std::string msg = "unknown name \"" + s->get() + "\"";
      const std::string guess = closest_match(s->get(), *allowed);
      if (!guess.empty()) msg += "; did you mean \"" + guess + "\"?";
      msg += " See docs/protocols.md, \"Key and button names\"";
      error(pos_of(e), field, msg);
      continue;
    }
    out.push_back(s->get());
  }
  return out;
}

std::string TableReader::with_found(const std::string& message, const toml::node& n) {
  // An unknown name quotes what was written already.
  if (message.find("found") != std::string::npos || message.starts_with("unknown value")) return message;
  return message + ", found " + type_name(n);
}

std::optional<SettingValue> TableReader::to_value(const toml::node& n) {
  if (const auto* b = n.as_boolean()) return SettingValue{b->get()};
  if (const auto* i = n.as_integer()) return SettingValue{i->get()};
  if (const auto* f = n.as_floating_point()) return SettingValue{f->get()};
  if (const auto* s = n.as_string()) return SettingValue{s->get()};
  return std::nullopt;
}

}  // namespace curvlab::harness::protocol
