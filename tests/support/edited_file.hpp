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

inline std::string edited_file(const std::string& path,
                               const std::vector<std::pair<std::string, std::string>>& replacements) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::string out = text.str();
  EXPECT_FALSE(out.empty()) << "cannot read " << path;
  for (const auto& [from, to] : replacements) {
    const auto at = out.find(from);
    EXPECT_NE(at, std::string::npos) << path << " has no '" << from << "'";
    if (at != std::string::npos) out.replace(at, from.size(), to);
  }
  return out;
}

}  // namespace curvlab::test
