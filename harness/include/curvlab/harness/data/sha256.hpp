// SHA-256 (FIPS 180-4) of a byte string, as 64 lowercase hex digits; used to
// fingerprint protocol texts stored with each session.
#pragma once

#include <string>
#include <string_view>

namespace curvlab::data {

std::string sha256_hex(std::string_view bytes);

}  // namespace curvlab::data
