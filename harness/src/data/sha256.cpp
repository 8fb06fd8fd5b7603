// SHA-256 through GNU Nettle (Debian nettle-dev), a maintained and audited
// implementation, rather than a hand-written one.
#include "curvlab/harness/data/sha256.hpp"

#include <nettle/sha2.h>

#include <array>
#include <cstdint>

namespace curvlab::data {

std::string sha256_hex(std::string_view bytes) {
  sha256_ctx ctx{};
  sha256_init(&ctx);
  sha256_update(&ctx, bytes.size(), reinterpret_cast<const std::uint8_t*>(bytes.data()));
  std::array<std::uint8_t, SHA256_DIGEST_SIZE> digest{};
  sha256_digest(&ctx, digest.size(), digest.data());
  static constexpr char hex[] = "0123456789abcdef";
  std::string out;
  out.reserve(2 * digest.size());
  for (const std::uint8_t b : digest) {
    out += hex[b >> 4];
    out += hex[b & 0xF];
  }
  return out;
}

}  // namespace curvlab::data
