#include "key_script.hpp"

#include "curvlab/harness/utf8.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

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
    const std::string form = key == "hand" ? "`hand left|right X Y Z [DELAY_MS]`" : "`KEY [DELAY_MS]`";
    if (key == "hand") {
      std::string side;
      words >> side;
      k.left_hand = side == "left";
      k.hand_m = hand_position(words);
      if ((side != "left" && side != "right") || !k.hand_m)
        return Error{Error::Kind::bad_input, where + "expected " + form +
                                                 " with the hand's lab position X Y Z in metres (each within 10)"};
    }
    if (words >> delay) {
      long long ms = -1;
      const auto [end, ec] = std::from_chars(delay.data(), delay.data() + delay.size(), ms);
      if (ec != std::errc() || end != delay.data() + delay.size() || ms < 0 || ms > 3'600'000)
        return Error{Error::Kind::bad_input, where + "expected " + form + " with DELAY_MS a whole number "
                                      "of milliseconds from 0 to 3600000, got '" + printable(delay) + "'"};
      k.delay_ns = static_cast<std::int64_t>(ms) * 1'000'000;
    }
    if (words >> extra)
      return Error{Error::Kind::bad_input, where + "expected " + form + ", got more after the delay: '" +
                            printable(extra) + "'"};
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

void KeyScriptPlayer::on_frame(bool waiting_for_input, std::int64_t now_ns) {
  if (finished() || armed_at_ns_ || !waiting_for_input) return;
  armed_at_ns_ = now_ns;
}

std::optional<ScriptedKey> KeyScriptPlayer::due(std::int64_t now_ns) {
  if (finished() || !armed_at_ns_) return std::nullopt;
  if (now_ns - *armed_at_ns_ < keys_[next_].delay_ns) return std::nullopt;
  armed_at_ns_.reset();
  return keys_[next_++];
}

}  // namespace curvlab::harness::desktop
