// Text files people write (protocols, operator and key scripts, trajectory
// and touch CSVs, mapping and calibration files) must be UTF-8: what curvlab
// stores from them goes into SQLite text and JSON, and a Latin-1 é (0xE9, as
// Windows Notepad saves it) would fail there mid-session instead of at load.
// Every reader checks its text with find_invalid_utf8 before using it.
// Pure and header-only, so every library of the harness can use it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace curvlab::harness {

// Where a text stops being UTF-8: the 1-based line and byte column of the
// first byte that cannot begin or continue a character there, and its value.
struct Utf8Fault {
  std::size_t line = 1;
  std::size_t column = 1;
  unsigned char byte = 0;
};

namespace utf8_detail {

// The length of the well-formed UTF-8 sequence at `at` (RFC 3629: no
// overlong forms, no surrogates, nothing above U+10FFFF), or 0.
inline std::size_t sequence_length(std::string_view s, std::size_t at) {
  const auto b = [&](std::size_t k) { return static_cast<unsigned char>(s[at + k]); };
  const unsigned char lead = b(0);
  if (lead < 0x80) return 1;
  std::size_t n = 0;
  unsigned char lo = 0x80;  // the second byte's range
  unsigned char hi = 0xBF;
  if (lead >= 0xC2 && lead <= 0xDF) {
    n = 2;
  } else if (lead >= 0xE0 && lead <= 0xEF) {
    n = 3;
    if (lead == 0xE0) lo = 0xA0;  // overlong
    if (lead == 0xED) hi = 0x9F;  // surrogates
  } else if (lead >= 0xF0 && lead <= 0xF4) {
    n = 4;
    if (lead == 0xF0) lo = 0x90;  // overlong
    if (lead == 0xF4) hi = 0x8F;  // above U+10FFFF
  } else {
    return 0;
  }
  if (at + n > s.size() || b(1) < lo || b(1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k)
    if (b(k) < 0x80 || b(k) > 0xBF) return 0;
  return n;
}

}  // namespace utf8_detail

// The first place where `text` is not UTF-8; nullopt when all of it is.
// `first_line` is the line number of the text's first line (a reader that
// checks one line at a time passes its line number).
inline std::optional<Utf8Fault> find_invalid_utf8(std::string_view text, std::size_t first_line = 1) {
  std::size_t line = first_line;
  std::size_t line_start = 0;
  for (std::size_t i = 0; i < text.size();) {
    if (text[i] == '\n') {
      ++line;
      line_start = ++i;
      continue;
    }
    const std::size_t n = utf8_detail::sequence_length(text, i);
    if (n == 0) return Utf8Fault{line, i - line_start + 1, static_cast<unsigned char>(text[i])};
    i += n;
  }
  return std::nullopt;
}

// "not UTF-8 (byte 0xE9 at column 12); save the file as UTF-8"
inline std::string utf8_fault_text(const Utf8Fault& f) {
  static constexpr char hex[] = "0123456789ABCDEF";
  std::string out = "not UTF-8 (byte 0x";
  out += hex[f.byte >> 4];
  out += hex[f.byte & 0xF];
  out += " at column " + std::to_string(f.column) + "); save the file as UTF-8";
  return out;
}

// "FILE:LINE: WHAT is not UTF-8 (byte 0xE9 at column 12); save the file as UTF-8"
inline std::string utf8_fault_message(const std::string& file, std::string_view what, const Utf8Fault& f) {
  std::string out = file;
  out += ':';
  out += std::to_string(f.line);
  out += ": ";
  out += what;
  out += " is ";
  out += utf8_fault_text(f);
  return out;
}

}  // namespace curvlab::harness
