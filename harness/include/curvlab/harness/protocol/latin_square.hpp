// Counterbalancing squares. A Williams design balances first-order carryover:
// for even n every condition follows every other exactly once; for odd n the
// square and its mirror image together (2n rows) do (Williams 1949).
#pragma once

#include "curvlab/harness/result.hpp"

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::protocol {

using Square = std::vector<std::vector<std::size_t>>;

// n rows for even n, 2n rows for odd n; entries 0..n-1. n ≥ 1.
Square williams_design(std::size_t n);

// Done when `square` has every row a permutation of 0..n-1 and every column
// too (a Latin square, or stacked Latin squares); else an Error (bad_input)
// giving the reason.
Result<Done> check_latin(const Square& square, std::size_t n);

// Row for 1-based participant number p: (p − 1) mod rows.
std::size_t row_for_participant(const Square& square, std::uint64_t participant);

}  // namespace curvlab::harness::protocol
