// Portable randomness for designs. std::shuffle and the std distributions are
// implementation-defined, so the same seed would give different trial orders
// under libstdc++ and libc++; these draws use only the raw 64-bit output of
// std::mt19937_64, whose sequence the standard fixes.
#pragma once

#include <cstdint>
#include <random>
#include <utility>
#include <vector>

namespace curvlab::harness::protocol {

using Engine = std::mt19937_64;

// SplitMix64 finalizer: decorrelates nearby seeds.
std::uint64_t mix_seed(std::uint64_t x);

// The seed a participant's session uses: mix_seed(seed ^ mix_seed(participant))
// when per_participant, else the protocol's seed itself.
std::uint64_t participant_seed(std::uint64_t protocol_seed, std::uint64_t participant,
                               bool per_participant);

// Uniform integer in [0, bound), bound ≥ 1: Lemire's multiply-shift with
// rejection, so there is no modulo bias.
std::uint64_t bounded(Engine& rng, std::uint64_t bound);

// Uniform double in [0, 1) from the top 53 bits.
double uniform01(Engine& rng);

// Fisher–Yates, from the last element down.
template <typename T>
void shuffle(std::vector<T>& v, Engine& rng) {
  for (std::size_t i = v.size(); i > 1; --i) {
    const auto j = static_cast<std::size_t>(bounded(rng, i));
    using std::swap;
    swap(v[i - 1], v[j]);
  }
}

}  // namespace curvlab::harness::protocol
