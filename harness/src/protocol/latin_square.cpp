#include "curvlab/harness/protocol/latin_square.hpp"

#include <cstdint>

namespace curvlab::harness::protocol {

Square williams_design(std::size_t n) {
  Square sq;
  if (n == 0) return sq;
  // First row 0, 1, n−1, 2, n−2, …; row r adds r (mod n) to every entry.
  std::vector<std::size_t> first;
  first.reserve(n);
  std::size_t lo = 1, hi = n - 1;
  first.push_back(0);
  for (std::size_t k = 1; k < n; ++k) first.push_back(k % 2 == 1 ? lo++ : hi--);
  for (std::size_t r = 0; r < n; ++r) {
    std::vector<std::size_t> row(n);
    for (std::size_t c = 0; c < n; ++c) row[c] = (first[c] + r) % n;
    sq.push_back(row);
  }
  if (n % 2 == 1) {
    // Odd n: one square cannot balance carryover; its mirror completes it.
    for (std::size_t r = 0; r < n; ++r) sq.emplace_back(sq[r].rbegin(), sq[r].rend());
  }
  return sq;
}

namespace {
Error not_latin(std::string reason) { return {Error::Kind::bad_input, std::move(reason)}; }
}  // namespace

Result<Done> check_latin(const Square& square, std::size_t n) {
  if (square.empty()) return not_latin("the square has no rows");
  if (square.size() % n != 0)
    return not_latin("expected a multiple of " + std::to_string(n) + " rows (one per order), found " +
           std::to_string(square.size()));
  for (std::size_t r = 0; r < square.size(); ++r) {
    if (square[r].size() != n)
      return not_latin("row " + std::to_string(r + 1) + " has " + std::to_string(square[r].size()) +
             " entries, expected " + std::to_string(n));
    std::vector<bool> seen(n, false);
    for (std::size_t v : square[r]) {
      if (v >= n || seen[v]) return not_latin("row " + std::to_string(r + 1) + " is not a permutation");
      seen[v] = true;
    }
  }
  // Columns: within each stacked n-row square every column is a permutation.
  for (std::size_t base = 0; base < square.size(); base += n) {
    for (std::size_t c = 0; c < n; ++c) {
      std::vector<bool> seen(n, false);
      for (std::size_t r = base; r < base + n; ++r) {
        const std::size_t v = square[r][c];
        if (seen[v])
          return not_latin("column " + std::to_string(c + 1) + " repeats an entry in rows " +
                 std::to_string(base + 1) + "–" + std::to_string(base + n));
        seen[v] = true;
      }
    }
  }
  return Done{};
}

std::size_t row_for_participant(const Square& square, std::uint64_t participant) {
  if (square.empty() || participant == 0) return 0;
  return static_cast<std::size_t>((participant - 1) % square.size());
}

}  // namespace curvlab::harness::protocol
