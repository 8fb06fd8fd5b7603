#include "curvlab/harness/runner/operator.hpp"

#include "curvlab/harness/utf8.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <utility>

namespace curvlab::harness::runner {

namespace {

constexpr std::array<std::pair<OperatorActionKind, std::string_view>, 7> kNames{{
    {OperatorActionKind::pause, "pause"},
    {OperatorActionKind::resume, "resume"},
    {OperatorActionKind::recenter, "recenter"},
    {OperatorActionKind::repeat, "repeat"},
    {OperatorActionKind::skip, "skip"},
    {OperatorActionKind::note, "note"},
    {OperatorActionKind::end, "end"},
}};

constexpr std::string_view kBlank = " \t\r";

std::string_view trim(std::string_view s) {
  const auto b = s.find_first_not_of(kBlank);
  if (b == std::string_view::npos) return {};
  return s.substr(b, s.find_last_not_of(kBlank) - b + 1);
}

// The next blank-separated word of `s` from `pos`; pos moves past it.
std::string_view word(std::string_view s, std::size_t& pos) {
  const auto b = s.find_first_not_of(kBlank, pos);
  if (b == std::string_view::npos) {
    pos = s.size();
    return {};
  }
  const auto e = std::min(s.find_first_of(kBlank, b), s.size());
  pos = e;
  return s.substr(b, e - b);
}

std::optional<double> seconds(std::string_view w) {
  if (w.empty()) return std::nullopt;
  const std::string text(w);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(v) || v < 0.0) return std::nullopt;
  return v;
}

// Concatenation without `"literal" + std::string`, which GCC 12 misreads (-Wrestrict).
std::string join(std::initializer_list<std::string_view> parts) {
  std::string out;
  for (const auto p : parts) out.append(p);
  return out;
}

Error bad(const std::string& where, const std::string& what) { return Error{Error::Kind::bad_input, join({where, ": ", what})}; }

// One non-blank, non-comment line.
Result<OperatorAction> parse_line(std::string_view line, const std::string& where) {
  std::size_t pos = 0;
  const auto t_word = word(line, pos);
  const auto t = seconds(t_word);
  if (!t)
    return bad(where, join({"expected SECONDS ACTION [TEXT] with SECONDS a number ≥ 0 (seconds since the session "
                            "started), got '", t_word, "'"}));
  const auto a_word = word(line, pos);
  const auto kind = parse_operator_action(a_word);
  if (!kind)
    return bad(where, join({"unknown action '", a_word, "'; expected pause, resume, recenter, repeat, skip, note or end"}));
  OperatorAction a;
  a.kind = *kind;
  a.at_ns = std::llround(*t * 1e9);
  if (*kind == OperatorActionKind::note) {
    // The text is verbatim: everything after the blank that follows "note".
    const std::string_view rest = pos < line.size() ? line.substr(pos + 1) : std::string_view{};
    if (trim(rest).empty()) return bad(where, "a note needs its text: SECONDS note TEXT");
    a.text = std::string(rest);
    while (!a.text.empty() && a.text.back() == '\r') a.text.pop_back();
    return a;
  }
  std::string_view rest = trim(line.substr(pos));
  if (const auto hash = rest.find('#'); hash != std::string_view::npos) rest = trim(rest.substr(0, hash));
  if (!rest.empty())
    return bad(where, join({"'", a_word, "' takes no text, got '", rest, "'"}));
  return a;
}

std::string two(std::int64_t v) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%02lld", static_cast<long long>(v));
  return buf;
}

std::string clock_text(std::int64_t ns) {
  if (ns < 0) return "--:--";
  const std::int64_t s = ns / 1'000'000'000;
  return join({std::to_string(s / 60), ":", two(s % 60)});
}

std::string seconds_text(std::int64_t ns) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f s", static_cast<double>(ns) * 1e-9);
  return buf;
}

std::string tracking_text(const OperatorStatus& s) {
  static constexpr const char* names[] = {"head", "left", "right"};
  std::string out = "tracking";
  for (std::size_t d = 0; d < 3; ++d) {
    out += std::string("  ") + names[d] + " ";
    out += s.tracked[d] ? std::string("ok") : join({"LOST ", s.lost_ns[d] >= 0 ? seconds_text(s.lost_ns[d]) : "?"});
  }
  return out;
}

}  // namespace

std::string_view to_string(OperatorActionKind kind) {
  for (const auto& [k, name] : kNames)
    if (k == kind) return name;
  return "unknown";
}

std::optional<OperatorActionKind> parse_operator_action(std::string_view name) {
  for (const auto& [k, n] : kNames)
    if (n == name) return k;
  return std::nullopt;
}

Result<std::vector<OperatorAction>> parse_operator_script(std::string_view text, const std::string& name) {
  // A note is stored as text; a Latin-1 byte would end the session at that
  // note instead of here.
  if (const auto fault = find_invalid_utf8(text))
    return Error{Error::Kind::bad_input, utf8_fault_message(name, "the operator script", *fault)};
  std::vector<OperatorAction> actions;
  std::size_t line_no = 0;
  std::size_t start = 0;
  while (start <= text.size()) {
    const auto nl = std::min(text.find('\n', start), text.size());
    const std::string_view line = text.substr(start, nl - start);
    start = nl + 1;
    ++line_no;
    const std::string_view body = trim(line);
    if (body.empty() || body.front() == '#') continue;
    auto a = parse_line(line, name + ":" + std::to_string(line_no));
    if (!a) return a.error();
    // Stored with the action's event: the file's name, not its folder (a
    // folder can name a person).
    a.value().source = "script " + std::filesystem::path(name).filename().string() + ":" + std::to_string(line_no);
    actions.push_back(std::move(a).value());
  }
  std::stable_sort(actions.begin(), actions.end(),
                   [](const OperatorAction& a, const OperatorAction& b) { return a.at_ns < b.at_ns; });
  return actions;
}

Result<std::vector<OperatorAction>> read_operator_script(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{Error::Kind::not_found, path + ": cannot read the operator script"};
  std::stringstream text;
  text << in.rdbuf();
  return parse_operator_script(text.str(), path);
}

void ScriptedActions::due(std::int64_t elapsed_ns, std::vector<OperatorAction>& out) {
  while (next_ < actions_.size() && actions_[next_].at_ns <= elapsed_ns) out.push_back(actions_[next_++]);
}

std::vector<std::string> status_lines(const OperatorStatus& s, std::optional<double> free_disk_gb) {
  std::vector<std::string> lines;
  lines.push_back(join({"participant ", s.participant, "   session ", std::to_string(s.session_id), "   protocol ",
                        s.protocol}));
  std::string trial = join({"trial ", s.trial > 0 ? std::to_string(s.trial) : "-", "/", std::to_string(s.trials)});
  if (s.attempt > 1) trial += join({" (attempt ", std::to_string(s.attempt), ")"});
  lines.push_back(join({"block ", s.block.empty() ? "-" : s.block, "   ", trial, "   ", s.condition}));
  std::string phase = join({"phase ", to_string(s.phase)});
  if (s.phase_left_ns >= 0) phase += join({"  ", seconds_text(s.phase_left_ns), " left"});
  if (s.paused) phase += "   PAUSED";
  if (s.ended) phase += "   session over";
  lines.push_back(join({phase, "   elapsed ", clock_text(s.elapsed_ns), "   remaining ~", clock_text(s.remaining_ns)}));
  lines.push_back(tracking_text(s));
  char buf[200];
  if (s.last_rt_ms >= 0.0)
    std::snprintf(buf, sizeof buf, "last response %s  RT %.0f ms", s.last_response.c_str(), s.last_rt_ms);
  else
    std::snprintf(buf, sizeof buf, "last response %s", s.last_response.empty() ? "-" : s.last_response.c_str());
  lines.emplace_back(buf);
  std::snprintf(buf, sizeof buf, "late frames %lld trial  %lld session   CPU %.2f ms   GPU %s",
                static_cast<long long>(s.late_trial), static_cast<long long>(s.late_session), s.cpu_ms,
                s.gpu_ms >= 0.0 ? (std::to_string(s.gpu_ms).substr(0, 5) + " ms").c_str() : "-");
  lines.emplace_back(buf);
  if (free_disk_gb)
    std::snprintf(buf, sizeof buf, "disk free %.1f GB   logger drops %llu", *free_disk_gb,
                  static_cast<unsigned long long>(s.logger_drops));
  else
    std::snprintf(buf, sizeof buf, "disk free ?   logger drops %llu", static_cast<unsigned long long>(s.logger_drops));
  lines.emplace_back(buf);
  if (!s.partner.empty()) lines.push_back(s.partner);
  if (s.logger_lock_wait_s > 0.0) {
    std::snprintf(buf, sizeof buf, "logger waiting %.0f s for another program's lock on the data file",
                  s.logger_lock_wait_s);
    lines.emplace_back(buf);
  }
  return lines;
}

}  // namespace curvlab::harness::runner
