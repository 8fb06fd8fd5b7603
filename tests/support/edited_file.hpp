// A shipped file's text with some of its lines changed, for tests that run a
// variant of a protocol: each `from` must occur (a test fails naming it).
#pragma once

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace curvlab::test {

inline std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_FALSE(text.str().empty()) << "cannot read " << path;
  return text.str();
}

// `text` with the first `from` replaced by `to`.
inline std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "no '" << from << "'";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

inline std::string edited_file(const std::string& path,
                               const std::vector<std::pair<std::string, std::string>>& replacements) {
  std::string out = read_text(path);
  for (const auto& [from, to] : replacements) out = replaced(std::move(out), from, to);
  return out;
}

}  // namespace curvlab::test
