#include "common.hpp"

#include "curvlab/harness/data/database.hpp"

#include <CLI/CLI.hpp>

#include <charconv>
#include <csignal>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace curvlab::harness::cli {
namespace {

std::string human(const Json& v) {
  if (v.is_number_float()) {
    std::ostringstream os;
    os << std::setprecision(12) << v.get<double>();
    return os.str();
  }
  if (v.is_string()) return v.get<std::string>();
  if (v.is_array()) {
    std::string out = "[";
    for (std::size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + human(v[i]);
    return out + "]";
  }
  return v.dump();
}

void print_human(const Json& doc, const std::string& indent) {
  std::size_t width = 0;
  for (const auto& [key, value] : doc.items()) width = std::max(width, key.size());
  for (const auto& [key, value] : doc.items()) {
    if (value.is_object()) {
      std::cout << indent << key << ":\n";
      print_human(value, indent + "  ");
    } else {
      std::cout << indent << std::left << std::setw(static_cast<int>(width) + 1)
                << (key + ":") << ' ' << human(value) << '\n';
    }
  }
}

}  // namespace

void raise(const harness::Error& e) {
  if (harness::exit_code(e) == 2) throw UsageError(e.message);
  throw RuntimeFailure(e.message);
}

void check_db_argument(const std::string& path) {
  // A folder is a mistake in the command, not a file to open: exit 2.
  if (std::error_code ec; std::filesystem::is_directory(path, ec))
    throw UsageError("--db " + path + ": is a folder; expected a database file (created when missing)");
  if (auto checked = data::check_data_file(path); !checked) raise(checked.error());
}

void print_result(const Json& doc, bool as_json) {
  if (as_json) {
    std::cout << doc.dump(2) << '\n';
  } else {
    print_human(doc, "");
  }
}

std::vector<double> parse_number_list(const std::string& text, const std::string& option,
                                      std::size_t expected_count) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    while (used < item.size() && std::isspace(static_cast<unsigned char>(item[used]))) ++used;
    if (used == 0 || used != item.size() || !std::isfinite(value))
      throw UsageError(option + ": '" + item + "' is not a finite number (expected " +
                       std::to_string(expected_count) + " comma-separated numbers)");
    out.push_back(value);
  }
  if (out.size() != expected_count)
    throw UsageError(option + ": expected " + std::to_string(expected_count) +
                     " comma-separated numbers, got " + std::to_string(out.size()));
  return out;
}

std::uint32_t check_msaa(int samples) {
  if (samples != 1 && samples != 2 && samples != 4 && samples != 8)
    throw UsageError("--msaa must be 1, 2, 4 or 8, got " + std::to_string(samples));
  return static_cast<std::uint32_t>(samples);
}

std::optional<std::uint32_t> parse_msaa(const std::string& text) {
  if (text == "auto") return std::nullopt;
  int samples = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), samples);
  if (ec != std::errc{} || end != text.data() + text.size())
    throw UsageError("--msaa must be auto, 1, 2, 4 or 8, got '" + text + "'");
  return check_msaa(samples);
}

void warn_if_msaa_clamped(std::uint32_t requested, std::uint32_t effective) {
  if (effective != 0 && effective < requested)
    std::cerr << "curvlab: warning: msaa " << requested << " is more than the Vulkan device supports; "
              << "drawing with " << effective << " samples per pixel\n";
}

std::pair<std::uint32_t, std::uint32_t> parse_size(const std::string& text, const std::string& option) {
  const auto x = text.find('x');
  try {
    if (x == std::string::npos) throw std::invalid_argument("no x");
    std::size_t used_w = 0;
    std::size_t used_h = 0;
    const long w = std::stol(text.substr(0, x), &used_w);
    const long h = std::stol(text.substr(x + 1), &used_h);
    if (used_w != x || used_h != text.size() - x - 1) throw std::invalid_argument("junk");
    if (w < 16 || h < 16 || w > 8192 || h > 8192)
      throw UsageError(option + " " + text + ": width and height must be between 16 and 8192 pixels");
    return {static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h)};
  } catch (const UsageError&) {
    throw;
  } catch (const std::exception&) {
    throw UsageError(option + " expects WIDTHxHEIGHT in pixels (e.g. 1024x1024), got '" + text + "'");
  }
}

void add_space_option(CLI::App* cmd, geometry::SpaceKind* kind) {
  cmd->add_option_function<std::string>(
         "--space", [kind](const std::string& text) { *kind = *geometry::parse_space_kind(text); },
         "space: S3, E3 or H3")
      ->required()
      ->check(CLI::IsMember({"S3", "E3", "H3", "s3", "e3", "h3"}));
}

void ignore_broken_pipes() {
#ifdef SIGPIPE
  std::signal(SIGPIPE, SIG_IGN);
#endif
}

}  // namespace curvlab::harness::cli
