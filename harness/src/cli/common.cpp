#include "common.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/protocol/diagnostic.hpp"

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

namespace {

// A command typed with a slip: up to two edits (a swapped pair of letters
// is two), or a third of a long word.
std::string closest_command(const std::string& word, const std::vector<std::string>& names) {
  const std::size_t limit = std::max<std::size_t>(2, word.size() / 3);
  std::string best;
  std::size_t best_d = limit + 1;
  for (const auto& n : names)
    if (const std::size_t d = protocol::edit_distance(word, n); d < best_d) {
      best_d = d;
      best = n;
    }
  return best;
}

}  // namespace

std::optional<std::string> misspelt_argument(CLI::App& app, int argc, const char* const* argv) {
  CLI::App* cmd = &app;
  std::string path = "curvlab";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") break;
    if (arg.rfind("--", 0) == 0) {
      const std::string name = arg.substr(0, arg.find('='));
      if (cmd->get_option_no_throw(name) != nullptr || app.get_option_no_throw(name) != nullptr) continue;
      std::vector<std::string> known;
      for (const CLI::Option* o : cmd->get_options())
        for (const auto& l : o->get_lnames()) known.push_back("--" + l);
      const std::string guess = closest_command(name, known);
      if (guess.empty()) return std::nullopt;
      return path + ": unknown option " + name + "; did you mean " + guess + "? (`" + path + " --help` lists them)";
    }
    if (arg.empty() || arg[0] == '-') continue;  // a short option, a negative number
    const auto subs = cmd->get_subcommands([](CLI::App*) { return true; });
    if (subs.empty()) continue;  // a positional argument or an option's value
    CLI::App* next = nullptr;
    std::vector<std::string> names;
    for (CLI::App* s : subs) {
      names.push_back(s->get_name());
      if (s->get_name() == arg) next = s;
    }
    if (next != nullptr) {
      cmd = next;
      path += " " + arg;
      continue;
    }
    const std::string guess = closest_command(arg, names);
    std::string all;
    for (const auto& n : names) all += (all.empty() ? "" : ", ") + n;
    return "'" + arg + "' is not a command of " + path + (guess.empty() ? "" : "; did you mean '" + guess + "'?") +
           " Expected one of: " + all;
  }
  return std::nullopt;
}

// The largest participant number a pseudonym's trailing digits may give:
// nine digits. A longer number is refused rather than folded onto another
// participant's seed and counterbalancing row.
constexpr std::uint64_t kMaxPseudonymNumber = 999'999'999;

// The participant number of a pseudonym: its trailing number (P07 → 7), 1
// when it has none (docs/runner.md, `curvlab run`). A trailing number
// of 0 or above kMaxPseudonymNumber is a UsageError naming --participant.
std::uint64_t number_from_pseudonym(const std::string& id) {
  std::size_t end = id.size();
  std::size_t begin = end;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(id[begin - 1]))) --begin;
  if (begin == end) return 1;
  const std::string digits = id.substr(begin, end - begin);
  const std::size_t significant = digits.find_first_not_of('0');
  if (significant == std::string::npos)
    throw UsageError("--participant " + id + ": its trailing number " + digits +
                     " is 0; participant numbers start at 1 (or give --participant-number N)");
  if (digits.size() - significant > 9)
    throw UsageError("--participant " + id + ": its trailing number " + digits + " is larger than " +
                     std::to_string(kMaxPseudonymNumber) +
                     ", the largest participant number a pseudonym gives; pass --participant-number N explicitly");
  return std::stoull(digits.substr(significant));
}

std::uint64_t participant_number(const std::string& participant, std::optional<std::uint64_t> number) {
  const std::uint64_t n = number ? *number : number_from_pseudonym(participant);
  if (n < 1) throw UsageError("--participant-number must be at least 1");
  return n;
}

}  // namespace curvlab::harness::cli
