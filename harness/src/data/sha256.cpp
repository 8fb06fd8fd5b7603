// SHA-256 through GNU Nettle (Debian nettle-dev), a maintained and audited
// implementation, rather than a hand-written one.
#include "curvlab/harness/data/sha256.hpp"

#include <nettle/sha2.h>

#include <array>
#include <cstdint>

namespace curvlab::harness::data {

struct Sha256::State {
  sha256_ctx ctx{};
};

Sha256::Sha256() : state_(std::make_unique<State>()) { sha256_init(&state_->ctx); }

Sha256::~Sha256() = default;

Sha256& Sha256::add(std::string_view bytes) {
  sha256_update(&state_->ctx, bytes.size(), reinterpret_cast<const std::uint8_t*>(bytes.data()));
  return *this;
}

std::string Sha256::hex() {
  std::array<std::uint8_t, SHA256_DIGEST_SIZE> digest{};
  sha256_digest(&state_->ctx, digest.size(), digest.data());
  static constexpr char hex[] = "0123456789abcdef";
  std::string out;
  out.reserve(2 * digest.size());
  for (const std::uint8_t b : digest) {
    out += hex[b >> 4];
    out += hex[b & 0xF];
  }
  return out;
}

std::string sha256_hex(std::string_view bytes) { return Sha256().add(bytes).hex(); }

}  // namespace curvlab::harness::data
