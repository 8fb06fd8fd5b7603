#include "curvlab/harness/protocol/diagnostic.hpp"

#include <algorithm>

namespace curvlab::harness::protocol {

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t subst = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, subst});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string closest_match(const std::string& word, const std::vector<std::string>& candidates) {
  // Typos only: up to a third of the word's length, at least 1, at most 3 edits.
  const std::size_t limit = std::clamp<std::size_t>(word.size() / 3, 1, 3);
  std::string best;
  std::size_t best_d = limit + 1;
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

std::string did_you_mean(const std::string& word, const std::vector<std::string>& candidates) {
  const std::string guess = closest_match(word, candidates);
  return guess.empty() ? std::string() : "; did you mean \"" + guess + "\"?";
}

std::string expected_one_of(const std::string& word, const std::vector<std::string>& allowed) {
  const std::string guess = did_you_mean(word, allowed);
  std::string out = guess.empty() ? ": expected one of " : guess + " Expected one of ";
  for (std::size_t i = 0; i < allowed.size(); ++i) out += (i ? ", \"" : "\"") + allowed[i] + "\"";
  return out;
}

std::string unknown_value(const std::string& word, const std::vector<std::string>& allowed) {
  return "unknown value \"" + word + "\"" + expected_one_of(word, allowed);
}

}  // namespace curvlab::harness::protocol
