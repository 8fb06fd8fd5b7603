// Session identity across files and machines: RFC 9562 UUIDs in the
// canonical lower-case text form (8-4-4-4-12 hex digits).
#pragma once

#include <cstdint>
#include <string>

namespace curvlab::harness::data {

// A version 7 UUID (RFC 9562 §5.7): 48 bits of Unix time in milliseconds,
// then 74 random bits, so that sessions sort by creation time.
std::string new_session_uuid();
// The same layout from given parts (for tests): unix_ms's low 48 bits, the
// random bits taken from rand_a (12 bits) and rand_b (62 bits).
std::string session_uuid_v7(std::uint64_t unix_ms, std::uint16_t rand_a, std::uint64_t rand_b);
// True for the canonical text form of any RFC 9562 UUID with variant 10.
bool is_session_uuid(const std::string& text);

}  // namespace curvlab::harness::data
