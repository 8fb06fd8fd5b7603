// The partner's clock (clock_sync.hpp) and the handshake's comparison
// (handshake.hpp), without a network.
#include <gtest/gtest.h>

#include <random>

#include <curvlab/harness/net/clock_sync.hpp>
#include <curvlab/harness/net/handshake.hpp>

#include "messages_fixture.hpp"

namespace net = curvlab::harness::net;

namespace {

// One exchange with a partner whose clock reads `offset` more than ours,
// taking `there` ns on the way out and `back` on the way back, answered
// after `hold` ns.
net::ClockSample exchange(std::int64_t t1, std::int64_t offset, std::int64_t there, std::int64_t hold,
                          std::int64_t back) {
  const std::int64_t t2 = t1 + there + offset;
  const std::int64_t t3 = t2 + hold;
  const std::int64_t t4 = t3 - offset + back;
  return {t1, t2, t3, t4};
}

}  // namespace

TEST(NetClock, SymmetricPathsGiveTheExactOffset) {
  for (std::int64_t offset : {0LL, 1'234'567'891LL, -987'654'321'000LL}) {
    const auto s = exchange(10'000'000, offset, 400'000, 30'000, 400'000);
    EXPECT_EQ(s.offset_ns(), offset);
    EXPECT_EQ(s.round_trip_ns(), 800'000);
  }
}

TEST(NetClock, AsymmetryShiftsTheOffsetByHalfItsDifferenceWithinTheUncertainty) {
  net::ClockEstimator est;
  ASSERT_TRUE(est.add(exchange(0, 5'000'000, 900'000, 10'000, 100'000)));
  const auto e = est.estimate();
  ASSERT_TRUE(e.valid);
  EXPECT_EQ(e.offset_ns - 5'000'000, (900'000 - 100'000) / 2);
  EXPECT_LE(std::llabs(e.offset_ns - 5'000'000), e.uncertainty_ns);
}

TEST(NetClock, TheShortestRoundTripInTheWindowWins) {
  // Queueing delays drawn at random on each path; one exchange meets empty
  // queues. The estimate must be that exchange's, exact.
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<std::int64_t> queue(0, 20'000'000);
  net::ClockEstimator est(32);
  const std::int64_t offset = -3'000'000'000LL;
  for (int i = 0; i < 32; ++i) {
    const std::int64_t t1 = 250'000'000LL * i;
    if (i == 17)
      ASSERT_TRUE(est.add(exchange(t1, offset, 200'000, 5'000, 200'000)));
    else
      ASSERT_TRUE(est.add(exchange(t1, offset, 200'000 + queue(rng), 5'000, 200'000 + queue(rng))));
  }
  const auto e = est.estimate();
  EXPECT_EQ(e.offset_ns, offset);
  EXPECT_EQ(e.round_trip_ns, 400'000);
  EXPECT_EQ(e.samples, 32u);
  EXPECT_EQ(est.to_local_ns(offset + 42), 42);
}

TEST(NetClock, TheWindowForgetsOldExchanges) {
  // The clocks moved (drift, or the partner restarted): after a window of
  // new exchanges the old, shorter one no longer decides.
  net::ClockEstimator est(4);
  ASSERT_TRUE(est.add(exchange(0, 1'000, 100, 0, 100)));
  for (int i = 1; i <= 4; ++i) ASSERT_TRUE(est.add(exchange(1'000'000 * i, 9'000, 500, 0, 500)));
  EXPECT_EQ(est.estimate().offset_ns, 9'000);
}

TEST(NetClock, ImpossibleExchangesAreNotKept) {
  net::ClockEstimator est;
  EXPECT_FALSE(est.add({100, 50, 40, 200}));  // answered before it was received
  EXPECT_FALSE(est.add({100, 0, 0, 50}));     // came back before it left
  EXPECT_FALSE(est.estimate().valid);
}

TEST(NetHandshake, TheSameStationsAgree) {
  EXPECT_FALSE(net::incompatibility(curvlab::test::hello(net::Role::host), curvlab::test::hello(net::Role::join)));
}

TEST(NetHandshake, ADifferentProtocolIsNamedWithBothHashes) {
  auto mine = curvlab::test::hello(net::Role::host);
  auto theirs = curvlab::test::hello(net::Role::join);
  theirs.protocol_sha256 = std::string(64, 'b');
  const auto why = net::incompatibility(mine, theirs);
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("The protocols differ"), std::string::npos) << *why;
  EXPECT_NE(why->find("aaaaaaaaaaaa..."), std::string::npos) << *why;
  EXPECT_NE(why->find("bbbbbbbbbbbb..."), std::string::npos) << *why;
  EXPECT_EQ(why->find("version"), std::string::npos) << *why;
}

TEST(NetHandshake, ADifferentVersionIsNamed) {
  auto mine = curvlab::test::hello(net::Role::join);
  auto theirs = curvlab::test::hello(net::Role::host);
  theirs.software_version = "0.2.0";
  const auto why = net::incompatibility(mine, theirs);
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("this station runs 0.1.0, the partner 0.2.0"), std::string::npos) << *why;
}

TEST(NetHandshake, EachDifferentParameterIsNamedWithBothValues) {
  auto mine = curvlab::test::hello(net::Role::host);
  auto theirs = net::make_hello(net::Role::join, "0.1.0", std::string(64, 'a'),
                                {{"space", "H3"}, {"table.edge_m", "1.27"}, {"cloth", "fast"}}, "CD");
  const auto why = net::incompatibility(mine, theirs);
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("space: this station S3, the partner H3"), std::string::npos) << *why;
  EXPECT_NE(why->find("rack: this station triangle-3, the partner (none)"), std::string::npos) << *why;
  EXPECT_NE(why->find("cloth: this station (none), the partner fast"), std::string::npos) << *why;
  EXPECT_EQ(why->find("table.edge_m"), std::string::npos) << *why;
}

TEST(NetHandshake, TheParameterDigestIgnoresOrder) {
  const auto a = net::make_hello(net::Role::host, "v", std::string(64, 'a'), {{"x", "1"}, {"y", "2"}}, "A");
  const auto b = net::make_hello(net::Role::join, "v", std::string(64, 'a'), {{"y", "2"}, {"x", "1"}}, "B");
  EXPECT_EQ(a.parameters_sha256, b.parameters_sha256);
  EXPECT_EQ(a.parameters, b.parameters);
}

TEST(NetHandshake, RolesAndGamesMustMatch) {
  auto mine = curvlab::test::hello(net::Role::host);
  auto theirs = curvlab::test::hello(net::Role::host);
  auto why = net::incompatibility(mine, theirs);
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("Both stations are hosts"), std::string::npos);
  theirs.role = net::Role::join;
  mine.game_uuid[0] = 1;
  EXPECT_FALSE(net::incompatibility(mine, theirs));  // a rejoin meets a new host: the host decides
  theirs.game_uuid[0] = 2;
  why = net::incompatibility(mine, theirs);
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("different games"), std::string::npos);
}
