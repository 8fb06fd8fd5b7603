// The shared-play codec (messages.hpp): every message survives a round trip;
// whatever else arrives — truncated, tampered, oversized, random or mutated
// bytes — is refused with a reason and never crashes the decoder.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>

#include "messages_fixture.hpp"

namespace net = curvlab::harness::net;
using curvlab::test::every_message;

namespace {

std::vector<std::uint8_t> bytes_of(const net::Message& m) { return net::encode(m); }

void set_u32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

}  // namespace

TEST(NetMessages, EveryTypeRoundTrips) {
  for (const auto& m : every_message()) {
    const auto b = bytes_of(m);
    const auto d = net::decode(b);
    ASSERT_TRUE(d.message) << net::to_string(net::type_of(m)) << ": " << net::to_string(d.failure);
    EXPECT_EQ(net::type_of(*d.message), net::type_of(m));
    EXPECT_TRUE(*d.message == m) << net::to_string(net::type_of(m));
  }
}

TEST(NetMessages, PoseFrameSizeIsFixed) {
  // Head, hands and cue at 90 Hz: 542 bytes a frame, 49 kB/s before ENet's headers.
  EXPECT_EQ(bytes_of(curvlab::test::pose_frame(curvlab::geometry::SpaceKind::H3, 1)).size(), 542u);
}

TEST(NetMessages, EveryTruncationIsRefused) {
  for (const auto& m : every_message()) {
    const auto b = bytes_of(m);
    for (std::size_t n = 0; n < b.size(); ++n) {
      const auto d = net::decode(std::span(b.data(), n));
      EXPECT_FALSE(d.message) << net::to_string(net::type_of(m)) << " cut at " << n;
      EXPECT_NE(d.failure, net::DecodeFailure::none);
    }
  }
}

TEST(NetMessages, HeaderTamperingIsRefusedWithItsReason) {
  const auto good = bytes_of(net::Ping{1, 2});
  auto b = good;
  b[0] = 'X';
  EXPECT_EQ(net::decode(b).failure, net::DecodeFailure::bad_magic);
  b = good;
  b[2] = net::kCodecVersion + 1;
  EXPECT_EQ(net::decode(b).failure, net::DecodeFailure::unsupported_version);
  b = good;
  b[3] = 0;
  EXPECT_EQ(net::decode(b).failure, net::DecodeFailure::unknown_type);
  b[3] = static_cast<std::uint8_t>(net::MessageType::avatar) + 1;
  EXPECT_EQ(net::decode(b).failure, net::DecodeFailure::unknown_type);
  b = good;
  set_u32(b, 4, 13);
  EXPECT_EQ(net::decode(b).failure, net::DecodeFailure::length_mismatch);
  b = good;
  b.push_back(0);
  set_u32(b, 4, static_cast<std::uint32_t>(b.size() - net::kHeaderBytes));
  EXPECT_EQ(net::decode(b).failure, net::DecodeFailure::trailing_bytes);
  std::vector<std::uint8_t> huge(net::kMaxMessageBytes + 1, 0);
  EXPECT_EQ(net::decode(huge).failure, net::DecodeFailure::oversized);
}

TEST(NetMessages, ValuesOutOfRangeAreRefused) {
  using curvlab::geometry::SpaceKind;
  // A tracked pose that is not an isometry of its space (an E3 frame sent as S3).
  auto p = curvlab::test::pose_frame(SpaceKind::E3, 1);
  p.space = SpaceKind::S3;
  EXPECT_EQ(net::decode(bytes_of(p)).failure, net::DecodeFailure::bad_value);
  // Not finite.
  p = curvlab::test::pose_frame(SpaceKind::H3, 1);
  p.pose[0].m[3][0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(net::decode(bytes_of(p)).failure, net::DecodeFailure::bad_value);
  // The same garbage in an untracked device's slot is finite, so it passes...
  p = curvlab::test::pose_frame(SpaceKind::H3, 1);
  p.pose[1].m[2][1] = 123.0;
  EXPECT_TRUE(net::decode(bytes_of(p)).message);
  // ...but not infinite there either.
  p.pose[1].m[2][1] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(net::decode(bytes_of(p)).failure, net::DecodeFailure::bad_value);
  // An aim point off any table; a negative speed; an event's ball out of range.
  auto s = curvlab::test::shot(1);
  s.toward_x_m = 1e5;
  EXPECT_EQ(net::decode(bytes_of(s)).failure, net::DecodeFailure::bad_value);
  s = curvlab::test::shot(1);
  s.cue_speed_m_s = -1.0;
  EXPECT_EQ(net::decode(bytes_of(s)).failure, net::DecodeFailure::bad_value);
  s = curvlab::test::shot(1);
  s.events[0].b = 200;
  EXPECT_EQ(net::decode(bytes_of(s)).failure, net::DecodeFailure::bad_value);
  // A control character in a text.
  net::Bye bye{net::Bye::Reason::done, "line\nbreak"};
  EXPECT_EQ(net::decode(bytes_of(bye)).failure, net::DecodeFailure::bad_value);
  // A protocol hash that is not 64 hex digits.
  auto h = curvlab::test::hello(net::Role::join);
  h.protocol_sha256 = "not a hash";
  EXPECT_EQ(net::decode(bytes_of(h)).failure, net::DecodeFailure::bad_value);
}

TEST(NetMessages, ListCountsBeyondTheirBoundAreRefusedBeforeAllocating) {
  // A Shot whose event count says 65535: refused as oversized, not read.
  auto b = bytes_of(curvlab::test::shot(1));
  const std::size_t count_at = net::kHeaderBytes + 4 + 1 + 1 + 8 + 4 + 5 * 8;
  ASSERT_EQ(b[count_at], 5);
  b[count_at] = 0xff;
  b[count_at + 1] = 0xff;
  EXPECT_EQ(net::decode(b).failure, net::DecodeFailure::oversized);
  // A count within the bound but beyond the bytes there.
  b[count_at] = 0x00;
  b[count_at + 1] = 0x04;  // 1024 events
  EXPECT_EQ(net::decode(b).failure, net::DecodeFailure::too_short);
}

TEST(NetMessagesDeathTest, EncodingBeyondABoundIsABrokenContract) {
  auto s = curvlab::test::shot(1);
  s.events.resize(net::kMaxEvents + 1);
  EXPECT_DEATH((void)net::encode(s), "Shot::events");
}

TEST(NetMessages, DropCountersCountByReason) {
  net::DropCounters c;
  c.count(net::decode(std::vector<std::uint8_t>{1, 2}).failure);
  c.count(net::decode(std::vector<std::uint8_t>(16, 0)).failure);
  EXPECT_EQ(c.by_reason[static_cast<int>(net::DecodeFailure::too_short)], 1u);
  EXPECT_EQ(c.by_reason[static_cast<int>(net::DecodeFailure::bad_magic)], 1u);
  EXPECT_EQ(c.total(), 2u);
}

// The decoder's fuzz test: seeded random buffers and mutations of valid
// messages (bit flips, byte overwrites, insertions, deletions, truncations,
// splices). The decoder must never crash (the sanitizer build checks reads
// too), and whatever it accepts must be a message that encodes back to a
// decodable equal one — so nothing half-checked gets through.
TEST(NetMessages, FuzzedBytesAreRefusedOrConsistent) {
  std::mt19937_64 rng(20261128);
  const auto messages = every_message();
  std::vector<std::vector<std::uint8_t>> seeds;
  for (const auto& m : messages) seeds.push_back(bytes_of(m));
  std::map<net::DecodeFailure, int> seen;
  int accepted = 0;
  auto check = [&](const std::vector<std::uint8_t>& b) {
    const auto d = net::decode(b);
    if (!d.message) {
      EXPECT_NE(d.failure, net::DecodeFailure::none);
      ++seen[d.failure];
      return;
    }
    ++accepted;
    const auto again = net::decode(net::encode(*d.message));
    ASSERT_TRUE(again.message);
    EXPECT_TRUE(*again.message == *d.message);
  };
  // Random bytes, some with a valid header in front.
  for (int i = 0; i < 20000; ++i) {
    std::vector<std::uint8_t> b(rng() % 700);
    for (auto& x : b) x = static_cast<std::uint8_t>(rng());
    if (i % 2 && b.size() >= net::kHeaderBytes) {
      b[0] = 'C';
      b[1] = 'L';
      b[2] = net::kCodecVersion;
      b[3] = static_cast<std::uint8_t>(1 + rng() % 7);
      set_u32(b, 4, static_cast<std::uint32_t>(b.size() - net::kHeaderBytes));
    }
    check(b);
  }
  // Mutations of valid messages.
  for (int i = 0; i < 60000; ++i) {
    auto b = seeds[rng() % seeds.size()];
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits && !b.empty(); ++e) {
      const std::size_t at = rng() % b.size();
      switch (rng() % 6) {
        case 0: b[at] ^= static_cast<std::uint8_t>(1u << (rng() % 8)); break;
        case 1: b[at] = static_cast<std::uint8_t>(rng()); break;
        case 2: b.insert(b.begin() + static_cast<std::ptrdiff_t>(at), static_cast<std::uint8_t>(rng())); break;
        case 3: b.erase(b.begin() + static_cast<std::ptrdiff_t>(at)); break;
        case 4: b.resize(at); break;
        case 5: {
          const auto& other = seeds[rng() % seeds.size()];
          b.insert(b.end(), other.begin(), other.begin() + static_cast<std::ptrdiff_t>(rng() % other.size()));
          break;
        }
      }
    }
    // Half the time keep the length field honest, so the payload checks are reached.
    if (i % 2 && b.size() >= net::kHeaderBytes)
      set_u32(b, 4, static_cast<std::uint32_t>(b.size() - net::kHeaderBytes));
    check(b);
  }
  // The mutations reached the payload checks, not only the header's.
  EXPECT_GT(seen[net::DecodeFailure::bad_value], 100);
  EXPECT_GT(seen[net::DecodeFailure::too_short], 100);
  EXPECT_GT(seen[net::DecodeFailure::length_mismatch], 100);
  EXPECT_GT(accepted, 100);  // byte flips in times, ids and ball frames stay valid
}
