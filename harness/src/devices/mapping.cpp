#include "curvlab/harness/devices/mapping.hpp"

#include "toml_reader.hpp"

#include <fstream>
#include <set>
#include <sstream>

namespace curvlab::harness::devices {
namespace {

namespace tr = harness::toml_reader;
using tr::FieldStatus;

// Thrown inside the parser only, turned into an Error value at its edge.
struct Fail {
  harness::Error error;
};

// "file:line:column: field: message", the form every mapping error takes.
harness::Error mapping_error(const std::string& file, tr::Pos pos, const std::string& field,
                             const std::string& message) {
  std::ostringstream os;
  os << file << ':' << pos.line << ':' << pos.column << ": " << field << ": " << message;
  return {harness::Error::Kind::bad_input, os.str()};
}

// Reads one mapping file, stopping at the first problem (a short file: one
// error at a time reads best). Field look-ups and type checks are the shared
// TOML readers'; the words are this format's own (docs/devices.md).
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const toml::source_region& where, const std::string& field,
                         const std::string& message) const {
    throw Fail{mapping_error(file_, tr::pos_of(where), field, message)};
  }

  void only_keys(const toml::table& table, const std::string& prefix,
                 const std::set<std::string>& allowed) const {
    const auto unknown = tr::unknown_keys(table, {allowed.begin(), allowed.end()});
    if (unknown.empty()) return;
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    fail(unknown.front().node->source(), prefix + unknown.front().key,
         "unknown key (expected one of: " + list + ")");
  }

  std::int64_t integer(const toml::table& table, const std::string& key, const std::string& prefix,
                       std::int64_t min, std::int64_t max) const {
    const auto f = tr::read_integer(table, key, min, max);
    switch (f.status) {
      case FieldStatus::ok: return f.value;
      case FieldStatus::absent: fail(table.source(), prefix + key, "missing (expected an integer)");
      case FieldStatus::out_of_range:
        fail(f.node->source(), prefix + key,
             "expected an integer in " + std::to_string(min) + " … " + std::to_string(max) +
                 ", got " + std::to_string(f.value));
      default: fail(f.node->source(), prefix + key, "expected an integer");
    }
  }

  std::optional<std::int64_t> optional_integer(const toml::table& table, const std::string& key,
                                               const std::string& prefix, std::int64_t min,
                                               std::int64_t max) const {
    if (!table.contains(key)) return std::nullopt;
    return integer(table, key, prefix, min, max);
  }

  std::string string(const toml::table& table, const std::string& key,
                     const std::string& prefix) const {
    const auto f = tr::read_string(table, key, /*allow_empty=*/false);
    if (f.ok()) return f.value;
    if (!f.present()) fail(table.source(), prefix + key, "missing (expected a string)");
    fail(f.node->source(), prefix + key, "expected a non-empty string");
  }

  const toml::array& tables(const toml::table& t, const std::string& key, const std::string& prefix,
                            const std::string& missing, const std::string& expected) const {
    const auto f = tr::read_array_of_tables(t, key);
    if (!f.present()) fail(t.source(), prefix + key, missing);
    if (!f.ok()) fail(f.node->source(), prefix + key, expected);
    return *f.value;
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
      if (const auto s = tr::read_bool(t, "signed"); s.present()) {
        if (!s.ok()) fail(s.node->source(), prefix + "signed", "expected true or false");
        a.is_signed = s.value;
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
    const toml::array& bindings = tables(t, "binding", prefix, "missing: add at least one [[device.binding]]",
                                         "expected an array of tables ([[device.binding]])");
    for (std::size_t i = 0; i < bindings.size(); ++i)
      d.bindings.push_back(binding(*bindings.get(i)->as_table(), prefix + "binding[" + std::to_string(i) + "]."));
    return d;
  }

  MappingFile file(const toml::table& root) const {
    only_keys(root, "", {"device"});
    const toml::array& devices = tables(root, "device", "", "missing: add at least one [[device]] table",
                                        "expected an array of tables ([[device]])");
    MappingFile out;
    out.file = file_;
    for (std::size_t i = 0; i < devices.size(); ++i)
      out.devices.push_back(device(*devices.get(i)->as_table(), "device[" + std::to_string(i) + "]."));
    return out;
  }

 private:
  std::string file_;
};

}  // namespace

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

harness::Result<MappingFile> parse_mapping(std::string_view text, const std::string& file_name) {
  // The same guarded parse as protocol files: toml++ 3.3 never sees text that
  // would reach its undefined behaviour.
  auto parsed = tr::parse(text, file_name);
  if (const auto* problem = std::get_if<tr::SyntaxProblem>(&parsed))
    return mapping_error(file_name, problem->pos, "(syntax)", problem->message);
  try {
    return Reader(file_name).file(std::get<toml::table>(parsed));
  } catch (const Fail& f) {
    return f.error;
  }
}

harness::Result<MappingFile> load_mapping(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    harness::Error e = mapping_error(path.string(), {}, "(file)", "cannot be read");
    e.kind = harness::Error::Kind::not_found;
    return e;
  }
  std::ostringstream text;
  text << in.rdbuf();
  return parse_mapping(text.str(), path.string());
}

}  // namespace curvlab::harness::devices
