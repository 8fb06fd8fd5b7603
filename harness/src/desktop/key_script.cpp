#include "key_script.hpp"

#include "curvlab/harness/utf8.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string_view>

namespace curvlab::harness::desktop {

using harness::Error;
using harness::Result;

namespace {

// A word of the script as a message shows it: bytes outside printable ASCII
// as \xNN, so a binary file given by mistake sends no control sequences to
// the terminal.
std::string printable(const std::string& word) {
  static constexpr char hex[] = "0123456789abcdef";
  std::string out;
  for (const char c : word) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7f) {
      out += c;
    } else {
      out += "\\x";
      out += hex[byte >> 4];
      out += hex[byte & 0xf];
    }
  }
  return out;
}

constexpr std::string_view kScriptPhases = "instructions, fixation, stimulus, response, iti, break, done, calibration";

// The phases a script line may count from: those the runner shows as a
// matter of course (not a pause or lost tracking).
std::optional<harness::io::Phase> script_phase(const std::string& name) {
  using harness::io::Phase;
  const auto phase = harness::io::parse_phase(name);
  if (!phase || *phase == Phase::paused || *phase == Phase::tracking_lost) return std::nullopt;
  return phase;
}

bool is_page(harness::io::Phase phase) {
  using harness::io::Phase;
  return phase == Phase::instructions || phase == Phase::break_page || phase == Phase::done ||
         phase == Phase::calibration;
}

}  // namespace

namespace {

// "X Y Z" of a hand line, in metres within 10 m of the origin.
std::optional<glm::dvec3> hand_position(std::istringstream& words) {
  glm::dvec3 p{0.0};
  for (int i = 0; i < 3; ++i) {
    std::string word;
    if (!(words >> word)) return std::nullopt;
    double v = 0.0;
    const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
    if (ec != std::errc() || end != word.data() + word.size() || !(std::abs(v) <= 10.0)) return std::nullopt;
    p[i] = v;
  }
  return p;
}

}  // namespace

Result<std::vector<ScriptedKey>> parse_key_script(const std::string& text,
                                                                         const std::string& origin) {
  if (const auto fault = harness::find_invalid_utf8(text))
    return Error{Error::Kind::bad_input, harness::utf8_fault_message(origin, "the key script", *fault)};
  std::vector<ScriptedKey> keys;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream words(line);
    std::string key;
    std::string delay;
    std::string extra;
    if (!(words >> key)) continue;  // blank or comment
    const std::string where = origin + ":" + std::to_string(number) + ": ";
    ScriptedKey k;
    k.line = number;
    std::transform(key.begin(), key.end(), key.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    k.name = key;
    const std::string form = key == "hand"   ? "`hand left|right X Y Z [PHASE+DELAY_MS | DELAY_MS]`"
                             : key == "look" ? "`look LEFT_DEG UP_DEG [PHASE+DELAY_MS | DELAY_MS]`"
                                             : "`KEY [PHASE+DELAY_MS | DELAY_MS]`";
    if (key == "hand") {
      std::string side;
      words >> side;
      k.left_hand = side == "left";
      k.hand_m = hand_position(words);
      if ((side != "left" && side != "right") || !k.hand_m)
        return Error{Error::Kind::bad_input, where + "expected " + form +
                                                 " with the hand's lab position X Y Z in metres (each within 10)"};
    }
    if (key == "look") {
      glm::dvec2 turn{};
      if (!(words >> turn.x >> turn.y) || !(std::abs(turn.x) <= 180.0) || !(std::abs(turn.y) <= 90.0))
        return Error{Error::Kind::bad_input,
                     where + "expected " + form + " with the turn left and up in degrees (within ±180 and ±90)"};
      k.look_deg = turn;
    }
    if (words >> delay) {
      // `PHASE+DELAY_MS`, `PHASE` or a bare `DELAY_MS`.
      std::string ms_text = delay;
      if (!delay.empty() && std::isalpha(static_cast<unsigned char>(delay.front()))) {
        const auto plus = delay.find('+');
        const std::string name = delay.substr(0, plus);
        k.phase = script_phase(name);
        if (!k.phase)
          return Error{Error::Kind::bad_input, where + "expected " + form + " with WHEN a phase (" +
                                                   std::string(kScriptPhases) + ") and +DELAY_MS, got '" +
                                                   printable(delay) + "'"};
        ms_text = plus == std::string::npos ? "0" : delay.substr(plus + 1);
      }
      long long ms = -1;
      const auto [end, ec] = std::from_chars(ms_text.data(), ms_text.data() + ms_text.size(), ms);
      if (ms_text.empty() || ec != std::errc() || end != ms_text.data() + ms_text.size() || ms < 0 ||
          ms > 3'600'000)
        return Error{Error::Kind::bad_input, where + "expected " + form + " with DELAY_MS a whole number "
                                      "of milliseconds from 0 to 3600000, got '" + printable(delay) + "'"};
      k.delay_ns = static_cast<std::int64_t>(ms) * 1'000'000;
    }
    if (words >> extra) {
      if (extra != "repeat")
        return Error{Error::Kind::bad_input, where + "expected " + form + " [repeat], got more after the delay: '" +
                                                 printable(extra) + "'"};
      if (!k.phase)
        return Error{Error::Kind::bad_input, where + "a `repeat` line presses its key at every start of a phase; "
                                                 "expected one, e.g. '" + printable(key) + " response+150 repeat'"};
      k.repeat = true;
      if (words >> extra)
        return Error{Error::Kind::bad_input, where + "expected " + form + " [repeat], got more after `repeat`: '" +
                                                 printable(extra) + "'"};
    }
    keys.push_back(std::move(k));
  }
  return keys;
}

Result<std::vector<ScriptedKey>> load_key_script(const std::string& path) {
  std::ifstream file(path);
  if (!file) return Error{Error::Kind::bad_input, path + ": cannot open the key script"};
  std::ostringstream text;
  text << file.rdbuf();
  return parse_key_script(text.str(), path);
}

std::optional<Error> check_key_script(const std::vector<ScriptedKey>& keys, const std::string& origin,
                                      const KeyScriptLimits& limits) {
  using harness::io::Phase;
  const auto answers = [&limits](const std::string& key) {
    return std::find(limits.answer_keys.begin(), limits.answer_keys.end(), key) != limits.answer_keys.end();
  };
  const auto ms = [](std::int64_t ns) { return std::to_string(ns / 1'000'000) + " ms"; };
  for (const auto& k : keys) {
    const std::string where = origin + ":" + std::to_string(k.line) + ": ";
    const std::string of = " in " + limits.protocol;
    if (!k.phase) {
      // A bare delay counts from the stimulus onset in a trial: an answer
      // must come before the response window closes.
      const std::int64_t window_ms = limits.stimulus_ms + limits.response_ms;
      if (k.name != "hand" && answers(k.name) && k.delay_ns >= window_ms * 1'000'000)
        return Error{Error::Kind::bad_input,
                     where + "'" + k.name + " " + ms(k.delay_ns) + "' would answer after the response window closes (" +
                         "stimulus and response last " + std::to_string(window_ms) + " ms" + of +
                         "); expected a delay below that, e.g. '" + k.name + " response+150'"};
      continue;
    }
    std::int64_t length_ms = -1;  // a page waits for its key
    std::string next;
    switch (*k.phase) {
      case Phase::fixation: length_ms = limits.fixation_ms; next = "stimulus"; break;
      case Phase::stimulus: length_ms = limits.stimulus_ms; next = "response"; break;
      case Phase::response: length_ms = limits.response_ms; next = "iti"; break;
      case Phase::iti: length_ms = limits.iti_ms; next = "next trial's fixation"; break;
      default: break;
    }
    const std::string phase_name(harness::io::to_string(*k.phase));
    if (length_ms == 0)
      return Error{Error::Kind::bad_input, where + "'" + k.name + " " + phase_name + "+…' names the " + phase_name +
                                               " phase, which lasts 0 ms" + of + "; expected a phase it shows"};
    if (length_ms > 0 && k.delay_ns >= length_ms * 1'000'000)
      return Error{Error::Kind::bad_input,
                   where + "'" + k.name + " " + phase_name + "+" + std::to_string(k.delay_ns / 1'000'000) +
                       "' would land in the " + next + ", not the " + phase_name + " (it lasts " +
                       std::to_string(length_ms) + " ms" + of + "); expected a delay below " +
                       std::to_string(length_ms) + " ms"};
    if (k.name != "hand" && answers(k.name) && (*k.phase == Phase::fixation || *k.phase == Phase::iti))
      return Error{Error::Kind::bad_input,
                   where + "'" + k.name + "' answers" + of + ", and an answer during " + phase_name +
                       " is an early input the trial drops; expected the stimulus or response phase (e.g. '" +
                       k.name + " response+150')"};
  }
  return std::nullopt;
}

// Standing rules the script has reached leave its lines in order.
void KeyScriptPlayer::take_rules() {
  while (next_ < keys_.size() && keys_[next_].repeat) rules_.push_back(Rule{keys_[next_++], false, std::nullopt});
}

void KeyScriptPlayer::on_frame(harness::io::Phase phase, bool waiting_for_input, std::int64_t now_ns) {
  take_rules();
  if (taking_) {
    // The frame that took the last key still shows what was on screen
    // before it: whatever follows is a new phase (or page).
    taking_ = false;
    last_phase_ = phase;
    entered_ = true;
    for (auto& r : rules_) r.pending = !r.armed_at_ns && r.key.phase == phase;
    return;
  }
  if (!finished() || !waiting_for_input || !is_page(phase) || phase == harness::io::Phase::calibration)
    idle_since_ns_.reset();
  else if (!idle_since_ns_)
    idle_since_ns_ = now_ns;
  const bool entry = !last_phase_ || *last_phase_ != phase;
  if (entry) entered_ = true;
  last_phase_ = phase;
  const auto ready = [&](const ScriptedKey& k, bool entered) {
    return k.phase ? *k.phase == phase && entered && (waiting_for_input || !is_page(phase)) : waiting_for_input;
  };
  bool armed_now = false;
  if (!finished() && !armed_at_ns_ && ready(keys_[next_], entered_)) {
    armed_at_ns_ = now_ns;
    entered_ = false;
    armed_now = true;
  }
  for (auto& r : rules_) {
    if (entry) r.pending = r.key.phase == phase;
    if (r.armed_at_ns || !r.pending || !ready(r.key, true)) continue;
    r.pending = false;
    // A line in order that is armed for this phase's start presses instead.
    if (!armed_now || keys_[next_].phase != phase) r.armed_at_ns = now_ns;
  }
}

std::string KeyScriptPlayer::ran_out_message(const std::string& script, harness::io::Phase page) const {
  return "the key script " + script + " ran out (its last key, line " + std::to_string(last_line()) +
         ", was pressed) and the " + std::string(harness::io::to_string(page)) + " page waited " +
         std::to_string(kRunOutNs / 1'000'000'000) + " s for a key; the session ends here, resumable";
}

std::optional<ScriptedKey> KeyScriptPlayer::due(std::int64_t now_ns) {
  std::optional<ScriptedKey> key;
  if (!finished() && armed_at_ns_ && now_ns - *armed_at_ns_ >= keys_[next_].delay_ns) {
    armed_at_ns_.reset();
    key = keys_[next_++];
  } else {
    for (auto& r : rules_)
      if (r.armed_at_ns && now_ns - *r.armed_at_ns >= r.key.delay_ns) {
        r.armed_at_ns.reset();
        key = r.key;
        break;
      }
  }
  if (!key) return std::nullopt;
  taking_ = true;
  idle_since_ns_.reset();
  ++pressed_;
  last_line_ = key->line;
  return key;
}

}  // namespace curvlab::harness::desktop
