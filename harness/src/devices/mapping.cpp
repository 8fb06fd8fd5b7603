#include "curvlab/harness/devices/mapping.hpp"

#include <toml++/toml.h>

#include <fstream>
#include <set>
#include <sstream>

namespace curvlab::devices {
namespace {

// Thrown inside the parser only, turned into a MappingError value at its edge.
struct Fail {
  MappingError error;
};

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const toml::source_region& where, const std::string& field,
                         const std::string& message) const {
    throw Fail{{file_, static_cast<int>(where.begin.line), static_cast<int>(where.begin.column),
                field, message}};
  }

  void only_keys(const toml::table& table, const std::string& prefix,
                 const std::set<std::string>& allowed) const {
    for (const auto& [key, node] : table) {
      if (allowed.count(std::string(key.str())) != 0) continue;
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      fail(node.source(), prefix + std::string(key.str()), "unknown key (expected one of: " + list + ")");
    }
  }

  std::int64_t integer(const toml::table& table, const std::string& key, const std::string& prefix,
                       std::int64_t min, std::int64_t max) const {
    const toml::node* node = table.get(key);
    if (node == nullptr) fail(table.source(), prefix + key, "missing (expected an integer)");
    const auto* value = node->as_integer();
    if (value == nullptr) fail(node->source(), prefix + key, "expected an integer");
    const std::int64_t v = value->get();
    if (v < min || v > max)
      fail(node->source(), prefix + key,
           "expected an integer in " + std::to_string(min) + " … " + std::to_string(max) +
               ", got " + std::to_string(v));
    return v;
  }

  std::optional<std::int64_t> optional_integer(const toml::table& table, const std::string& key,
                                               const std::string& prefix, std::int64_t min,
                                               std::int64_t max) const {
    if (!table.contains(key)) return std::nullopt;
    return integer(table, key, prefix, min, max);
  }

  std::string string(const toml::table& table, const std::string& key,
                     const std::string& prefix) const {
    const toml::node* node = table.get(key);
    if (node == nullptr) fail(table.source(), prefix + key, "missing (expected a string)");
    const auto* value = node->as_string();
    if (value == nullptr || value->get().empty())
      fail(node->source(), prefix + key, "expected a non-empty string");
    return value->get();
  }

  Binding binding(const toml::table& t, const std::string& prefix) const {
    Binding b;
    b.response = string(t, "response", prefix);
    const std::string kind = string(t, "kind", prefix);
    if (kind == "bit") {
      only_keys(t, prefix, {"response", "kind", "byte", "bit"});
      b.input = BitBinding{static_cast<int>(integer(t, "byte", prefix, 0, 63)),
                           static_cast<int>(integer(t, "bit", prefix, 0, 7))};
    } else if (kind == "key") {
      only_keys(t, prefix, {"response", "kind", "keycode", "first_byte", "last_byte"});
      KeyBinding k;
      k.keycode = static_cast<std::uint8_t>(integer(t, "keycode", prefix, 1, 255));
      k.first_byte = static_cast<int>(optional_integer(t, "first_byte", prefix, 0, 63).value_or(2));
      k.last_byte = static_cast<int>(optional_integer(t, "last_byte", prefix, 0, 63).value_or(7));
      if (k.last_byte < k.first_byte)
        fail(t.get("last_byte")->source(), prefix + "last_byte", "must not be below first_byte");
      b.input = k;
    } else if (kind == "axis") {
      only_keys(t, prefix,
                {"response", "kind", "byte", "bits", "signed", "above", "below", "release"});
      AxisBinding a;
      a.byte = static_cast<int>(integer(t, "byte", prefix, 0, 63));
      a.bits = static_cast<int>(optional_integer(t, "bits", prefix, 8, 16).value_or(8));
      if (a.bits != 8 && a.bits != 16)
        fail(t.get("bits")->source(), prefix + "bits", "expected 8 or 16");
      if (const toml::node* s = t.get("signed")) {
        if (!s->is_boolean()) fail(s->source(), prefix + "signed", "expected true or false");
        a.is_signed = s->as_boolean()->get();
      }
      const std::int64_t lo = a.is_signed ? -(std::int64_t{1} << (a.bits - 1)) : 0;
      const std::int64_t hi = a.is_signed ? (std::int64_t{1} << (a.bits - 1)) - 1
                                          : (std::int64_t{1} << a.bits) - 1;
      const bool above = t.contains("above");
      if (above == t.contains("below"))
        fail(t.source(), prefix + "above", "give exactly one of 'above' or 'below' (the press threshold)");
      a.direction = above ? AxisBinding::Direction::Above : AxisBinding::Direction::Below;
      const std::string threshold_key = above ? "above" : "below";
      a.press_at = static_cast<int>(integer(t, threshold_key, prefix, lo, hi));
      a.release_at = static_cast<int>(optional_integer(t, "release", prefix, lo, hi).value_or(a.press_at));
      if (above ? a.release_at > a.press_at : a.release_at < a.press_at)
        fail(t.get("release")->source(), prefix + "release",
             std::string("must be on the released side of '") + threshold_key + "' (" +
                 (above ? "≤ " : "≥ ") + std::to_string(a.press_at) + ")");
      b.input = a;
    } else {
      fail(t.get("kind")->source(), prefix + "kind",
           "expected \"bit\", \"key\" or \"axis\", got \"" + kind + "\"");
    }
    return b;
  }

  DeviceMapping device(const toml::table& t, const std::string& prefix) const {
    only_keys(t, prefix,
              {"name", "vendor_id", "product_id", "usage_page", "usage", "report_id", "binding"});
    DeviceMapping d;
    d.name = string(t, "name", prefix);
    auto u16 = [&](const char* key) -> std::optional<std::uint16_t> {
      if (auto v = optional_integer(t, key, prefix, 0, 0xFFFF)) return static_cast<std::uint16_t>(*v);
      return std::nullopt;
    };
    d.match.vendor_id = u16("vendor_id");
    d.match.product_id = u16("product_id");
    d.match.usage_page = u16("usage_page");
    d.match.usage = u16("usage");
    if (!d.match.vendor_id && !d.match.product_id && !d.match.usage_page && !d.match.usage)
      fail(t.source(), prefix + "vendor_id",
           "missing: a device is matched by vendor_id/product_id and/or usage_page/usage "
           "(see `curvlab devices`)");
    if (auto id = optional_integer(t, "report_id", prefix, 1, 255))
      d.report_id = static_cast<std::uint8_t>(*id);
    const toml::node* bindings = t.get("binding");
    if (bindings == nullptr)
      fail(t.source(), prefix + "binding", "missing: add at least one [[device.binding]]");
    const auto* array = bindings->as_array();
    if (array == nullptr || !array->is_array_of_tables() || array->empty())
      fail(bindings->source(), prefix + "binding", "expected an array of tables ([[device.binding]])");
    for (std::size_t i = 0; i < array->size(); ++i)
      d.bindings.push_back(binding(*array->get(i)->as_table(),
                                   prefix + "binding[" + std::to_string(i) + "]."));
    return d;
  }

 private:
  std::string file_;
};

}  // namespace

std::string MappingError::what() const {
  std::ostringstream os;
  os << file << ':' << line << ':' << column << ": " << field << ": " << message;
  return os.str();
}

bool DeviceMatch::matches(const HidDeviceInfo& info) const {
  return (!vendor_id || *vendor_id == info.vendor_id) &&
         (!product_id || *product_id == info.product_id) &&
         (!usage_page || *usage_page == info.usage_page) && (!usage || *usage == info.usage);
}

const DeviceMapping* MappingFile::find(const HidDeviceInfo& info) const {
  for (const auto& d : devices)
    if (d.match.matches(info)) return &d;
  return nullptr;
}

std::variant<MappingFile, MappingError> parse_mapping(std::string_view text,
                                                      const std::string& file_name) {
  toml::table root;
  try {
    root = toml::parse(text, file_name);
  } catch (const toml::parse_error& e) {
    return MappingError{file_name, static_cast<int>(e.source().begin.line),
                        static_cast<int>(e.source().begin.column), "(syntax)",
                        std::string(e.description())};
  }
  const Reader reader(file_name);
  try {
    reader.only_keys(root, "", {"device"});
    const toml::node* devices = root.get("device");
    if (devices == nullptr)
      reader.fail(root.source(), "device", "missing: add at least one [[device]] table");
    const auto* array = devices->as_array();
    if (array == nullptr || !array->is_array_of_tables() || array->empty())
      reader.fail(devices->source(), "device", "expected an array of tables ([[device]])");
    MappingFile out;
    out.file = file_name;
    for (std::size_t i = 0; i < array->size(); ++i)
      out.devices.push_back(
          reader.device(*array->get(i)->as_table(), "device[" + std::to_string(i) + "]."));
    return out;
  } catch (const Fail& f) {
    return f.error;
  }
}

std::variant<MappingFile, MappingError> load_mapping(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return MappingError{path.string(), 0, 0, "(file)", "cannot be read"};
  std::ostringstream text;
  text << in.rdbuf();
  return parse_mapping(text.str(), path.string());
}

}  // namespace curvlab::devices
