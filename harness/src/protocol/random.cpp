#include "curvlab/harness/protocol/random.hpp"

namespace curvlab::harness::protocol {

std::uint64_t mix_seed(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

std::uint64_t participant_seed(std::uint64_t protocol_seed, std::uint64_t participant,
                               bool per_participant) {
  if (!per_participant) return protocol_seed;
  return mix_seed(protocol_seed ^ mix_seed(participant));
}

namespace {
// The full 128-bit product a·b as (high, low) from 32-bit halves: standard
// C++ has no 128-bit integer, and the draw must be the same everywhere.
struct Wide {
  std::uint64_t hi, lo;
};
Wide multiply(std::uint64_t a, std::uint64_t b) {
  const std::uint64_t a_lo = a & 0xFFFFFFFFu, a_hi = a >> 32;
  const std::uint64_t b_lo = b & 0xFFFFFFFFu, b_hi = b >> 32;
  const std::uint64_t ll = a_lo * b_lo, lh = a_lo * b_hi, hl = a_hi * b_lo, hh = a_hi * b_hi;
  const std::uint64_t mid = (ll >> 32) + (lh & 0xFFFFFFFFu) + (hl & 0xFFFFFFFFu);
  return {hh + (lh >> 32) + (hl >> 32) + (mid >> 32), (mid << 32) | (ll & 0xFFFFFFFFu)};
}
}  // namespace

std::uint64_t bounded(Engine& rng, std::uint64_t bound) {
  // Lemire (2019), "Fast random integer generation in an interval": the high
  // word of x·bound, rejecting the few x that would bias the result.
  Wide m = multiply(rng(), bound);
  if (m.lo < bound) {
    const std::uint64_t threshold = (0 - bound) % bound;
    while (m.lo < threshold) m = multiply(rng(), bound);
  }
  return m.hi;
}

double uniform01(Engine& rng) {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

}  // namespace curvlab::harness::protocol
