#include "curvlab/harness/data/uuid.hpp"

#include <array>
#include <chrono>
#include <random>

namespace curvlab::harness::data {

std::string session_uuid_v7(std::uint64_t unix_ms, std::uint16_t rand_a, std::uint64_t rand_b) {
  std::array<unsigned char, 16> b{};
  for (int i = 0; i < 6; ++i) b[static_cast<std::size_t>(i)] = static_cast<unsigned char>(unix_ms >> (8 * (5 - i)));
  b[6] = static_cast<unsigned char>(0x70 | ((rand_a >> 8) & 0x0F));  // version 7
  b[7] = static_cast<unsigned char>(rand_a);
  b[8] = static_cast<unsigned char>(0x80 | ((rand_b >> 56) & 0x3F));  // variant 10
  for (int i = 9; i < 16; ++i) b[static_cast<std::size_t>(i)] = static_cast<unsigned char>(rand_b >> (8 * (15 - i)));
  static constexpr char hex[] = "0123456789abcdef";
  std::string out;
  out.reserve(36);
  for (std::size_t i = 0; i < b.size(); ++i) {
    if (i == 4 || i == 6 || i == 8 || i == 10) out += '-';
    out += hex[b[i] >> 4];
    out += hex[b[i] & 0x0F];
  }
  return out;
}

std::string new_session_uuid() {
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                      std::chrono::system_clock::now().time_since_epoch())
                      .count();
  std::random_device rd;
  const std::uint64_t hi = rd(), lo = rd(), extra = rd();
  return session_uuid_v7(static_cast<std::uint64_t>(ms), static_cast<std::uint16_t>(extra),
                         (hi << 32) | lo);
}

bool is_session_uuid(const std::string& t) {
  if (t.size() != 36) return false;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const bool dash = i == 8 || i == 13 || i == 18 || i == 23;
    const char c = t[i];
    if (dash ? c != '-' : !((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return t[19] == '8' || t[19] == '9' || t[19] == 'a' || t[19] == 'b';
}

}  // namespace curvlab::harness::data
