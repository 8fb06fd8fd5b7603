// Two links on the loopback (link.hpp), directly and through the seeded UDP
// relay that loses, delays and reorders datagrams (tests/support/udp_relay.hpp).
// Nothing here asserts a duration: loops wait for what must happen, with a
// cap far above what it takes, so a busy machine is slow, not red.
#include <gtest/gtest.h>

#include <enet/enet.h>

#include <functional>

#include <curvlab/harness/net/link.hpp>

#include "messages_fixture.hpp"
#include "offset_clock.hpp"
#include "udp_relay.hpp"

namespace net = curvlab::harness::net;

namespace {

struct Station {
  explicit Station(net::Link l) : link(std::move(l)) {}
  net::Link link;
  std::vector<net::Received> got;
  int connects = 0, disconnects = 0;

  void poll(int ms) {
    auto p = link.poll(ms);
    for (auto& r : p.messages) got.push_back(std::move(r));
    connects += p.connected;
    disconnects += p.disconnected;
  }
  template <class T>
  std::vector<T> all() const {
    std::vector<T> out;
    for (const auto& r : got)
      if (auto* m = std::get_if<T>(&r.message)) out.push_back(*m);
    return out;
  }
};

// Polls until `done`, at most `rounds` times per station (each poll waits at
// most 2 ms for an event).
bool pump(std::initializer_list<Station*> stations, const std::function<bool()>& done, int rounds = 15000) {
  for (int i = 0; i < rounds; ++i) {
    for (Station* s : stations) s->poll(2);
    if (done()) return true;
  }
  return false;
}

const curvlab::harness::io::SteadyClock steady;

Station host_station(const curvlab::harness::io::Clock& clock = steady, std::uint16_t port = 0) {
  auto l = net::Link::listen("127.0.0.1", port, clock);
  if (!l) ADD_FAILURE() << l.error().message;
  return Station(std::move(l).value());
}
Station join_station(std::uint16_t port, const curvlab::harness::io::Clock& clock = steady) {
  auto l = net::Link::join("127.0.0.1", port, clock);
  if (!l) ADD_FAILURE() << l.error().message;
  return Station(std::move(l).value());
}

}  // namespace

TEST(NetLink, AddressesAreParsedOrRefusedClearly) {
  auto a = net::Link::parse_address("192.168.1.20:7777");
  ASSERT_TRUE(a);
  EXPECT_EQ(a->first, "192.168.1.20");
  EXPECT_EQ(a->second, 7777);
  for (const char* bad : {"192.168.1.20", ":7777", "host:", "host:0", "host:70000", "host:77x"}) {
    auto r = net::Link::parse_address(bad);
    ASSERT_FALSE(r) << bad;
    EXPECT_NE(r.error().message.find("--partner"), std::string::npos);
  }
}

TEST(NetLink, CarriesEveryMessageInOrder) {
  ASSERT_TRUE(net::built_with_enet());
  Station host = host_station();
  Station join = join_station(host.link.port());
  ASSERT_TRUE(pump({&host, &join}, [&] { return host.link.connected() && join.link.connected(); }));
  EXPECT_EQ(host.connects, 1);
  EXPECT_EQ(join.connects, 1);

  ASSERT_TRUE(host.link.send(curvlab::test::hello(net::Role::host)));
  ASSERT_TRUE(join.link.send(curvlab::test::hello(net::Role::join)));
  for (std::uint32_t i = 0; i < 20; ++i) {
    ASSERT_TRUE(join.link.send(curvlab::test::shot(i)));
    ASSERT_TRUE(join.link.send(curvlab::test::pose_frame(curvlab::geometry::SpaceKind::S3, i + 1)));
  }
  ASSERT_TRUE(pump({&host, &join}, [&] { return host.all<net::Shot>().size() == 20 && !join.all<net::Hello>().empty(); }));
  const auto shots = host.all<net::Shot>();
  for (std::uint32_t i = 0; i < 20; ++i) EXPECT_TRUE(shots[i] == curvlab::test::shot(i)) << i;
  EXPECT_FALSE(net::incompatibility(host.all<net::Hello>().at(0), join.all<net::Hello>().at(0)));
  const auto poses = host.all<net::PoseFrame>();
  ASSERT_FALSE(poses.empty());
  for (std::size_t i = 1; i < poses.size(); ++i) EXPECT_GT(poses[i].sequence, poses[i - 1].sequence);
  EXPECT_EQ(host.link.counters().dropped.total(), 0u);
  EXPECT_GT(host.link.counters().bytes_received, 20u * 542u);
}

TEST(NetLink, AStationThatDiffersIsToldWhyAndLeft) {
  Station host = host_station();
  Station join = join_station(host.link.port());
  ASSERT_TRUE(pump({&host, &join}, [&] { return host.link.connected() && join.link.connected(); }));
  auto theirs = curvlab::test::hello(net::Role::join);
  theirs.protocol_sha256 = std::string(64, 'c');
  ASSERT_TRUE(join.link.send(theirs));
  ASSERT_TRUE(pump({&host, &join}, [&] { return !host.all<net::Hello>().empty(); }));
  const auto why = net::incompatibility(curvlab::test::hello(net::Role::host), host.all<net::Hello>()[0]);
  ASSERT_TRUE(why);
  host.link.close(net::Bye{net::Bye::Reason::incompatible, *why}, 2000);
  ASSERT_TRUE(pump({&join}, [&] { return join.disconnects == 1; }));
  const auto byes = join.all<net::Bye>();
  ASSERT_EQ(byes.size(), 1u);
  EXPECT_EQ(byes[0].reason, net::Bye::Reason::incompatible);
  EXPECT_NE(byes[0].text.find("The protocols differ"), std::string::npos) << byes[0].text;
}

TEST(NetLink, MalformedDatagramsAreDroppedAndCounted) {
  Station host = host_station();
  // A rogue peer speaking ENet but not curvlab's codec.
  ENetHost* rogue = enet_host_create(nullptr, 1, 3, 0, 0);
  ASSERT_NE(rogue, nullptr);
  ENetAddress a{};
  enet_address_set_host_ip(&a, "127.0.0.1");
  a.port = host.link.port();
  ENetPeer* peer = enet_host_connect(rogue, &a, 3, 0);
  ENetEvent ev;
  bool up = false;
  ASSERT_TRUE(pump({&host}, [&] {
    while (enet_host_service(rogue, &ev, 0) > 0)
      if (ev.type == ENET_EVENT_TYPE_CONNECT) up = true;
    return up && host.link.connected();
  }));
  const std::vector<std::uint8_t> garbage[] = {
      {1, 2, 3}, {'C', 'L', 9, 1, 0, 0, 0, 0}, {'C', 'L', 1, 5, 200, 0, 0, 0}};
  for (const auto& g : garbage)
    enet_peer_send(peer, 1, enet_packet_create(g.data(), g.size(), ENET_PACKET_FLAG_RELIABLE));
  auto ok = net::encode(net::GameState{});
  enet_peer_send(peer, 1, enet_packet_create(ok.data(), ok.size(), ENET_PACKET_FLAG_RELIABLE));
  enet_host_flush(rogue);
  ASSERT_TRUE(pump({&host}, [&] {
    enet_host_service(rogue, &ev, 0);
    return !host.got.empty();
  }));
  const auto c = host.link.counters();
  EXPECT_EQ(c.dropped.total(), 3u);
  EXPECT_EQ(c.dropped.by_reason[static_cast<int>(net::DecodeFailure::too_short)], 1u);
  EXPECT_EQ(c.dropped.by_reason[static_cast<int>(net::DecodeFailure::unsupported_version)], 1u);
  EXPECT_EQ(c.dropped.by_reason[static_cast<int>(net::DecodeFailure::length_mismatch)], 1u);
  ASSERT_EQ(host.got.size(), 1u);  // only the good one
  EXPECT_EQ(net::type_of(host.got[0].message), net::MessageType::game_state);
  enet_peer_reset(peer);
  enet_host_destroy(rogue);
}

TEST(NetLink, AJoinerThatIsKilledComesBackAndTheHostSeesBoth) {
  Station host = host_station();
  const std::uint16_t port = host.link.port();
  {
    Station join = join_station(port);
    ASSERT_TRUE(pump({&host, &join}, [&] { return host.connects == 1 && join.link.connected(); }));
  }  // gone without a Bye
  ASSERT_TRUE(pump({&host}, [&] { return host.disconnects == 1; }));
  EXPECT_FALSE(host.link.connected());
  Station again = join_station(port);
  ASSERT_TRUE(pump({&host, &again}, [&] { return host.connects == 2 && again.link.connected(); }));
  ASSERT_TRUE(again.link.send(curvlab::test::shot(3)));
  ASSERT_TRUE(pump({&host, &again}, [&] { return host.all<net::Shot>().size() == 1; }));
}

TEST(NetLink, AJoinerReconnectsToAHostThatCameBack) {
  std::uint16_t port = 0;
  Station join = [&] {
    Station host = host_station();
    port = host.link.port();
    Station j = join_station(port);
    EXPECT_TRUE(pump({&host, &j}, [&] { return host.link.connected() && j.link.connected(); }));
    return j;
  }();  // the host is gone
  ASSERT_TRUE(pump({&join}, [&] { return join.disconnects == 1; }));
  Station host = host_station(steady, port);
  join.link.reconnect();
  ASSERT_TRUE(pump({&host, &join}, [&] { return host.link.connected() && join.link.connected(); }));
  EXPECT_EQ(join.connects, 2);
}

// The acceptance condition of the network layer: 5% loss and 50 ms delay
// each way (with jitter and reordering), the joiner's clock 1.5 s ahead.
// Every reliable message arrives once, in order, equal; poses are never
// delivered out of order; the clock estimate holds the true offset within
// its stated uncertainty.
TEST(NetLink, ThroughALossyDelayingReorderingRelay) {
  const std::int64_t true_offset = 1'500'000'000;
  const curvlab::test::OffsetClock joiner_clock(true_offset);
  Station host = host_station();
  std::string error;
  auto relay = curvlab::test::UdpRelay::start(
      {.target_port = host.link.port(), .loss = 0.05, .delay_ns = 50'000'000, .jitter_ns = 10'000'000,
       .reorder = 0.05, .seed = 42},
      &error);
  ASSERT_TRUE(relay) << error;
  Station join = join_station(relay->port(), joiner_clock);
  ASSERT_TRUE(pump({&host, &join}, [&] { return host.link.connected() && join.link.connected(); }));

  const std::uint32_t n = 30;
  std::uint32_t sent_poses = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    ASSERT_TRUE(join.link.send(curvlab::test::shot(2 * i + 1)));
    ASSERT_TRUE(host.link.send(curvlab::test::shot(2 * i)));
    for (int f = 0; f < 3; ++f) {
      ASSERT_TRUE(join.link.send(curvlab::test::pose_frame(curvlab::geometry::SpaceKind::H3, ++sent_poses)));
      host.poll(2);
      join.poll(2);
    }
  }
  ASSERT_TRUE(pump({&host, &join}, [&] {
    return host.all<net::Shot>().size() == n && join.all<net::Shot>().size() == n &&
           host.link.clock().samples >= 8 && join.link.clock().samples >= 8;
  }));
  const auto at_host = host.all<net::Shot>();
  const auto at_join = join.all<net::Shot>();
  for (std::uint32_t i = 0; i < n; ++i) {
    EXPECT_TRUE(at_host[i] == curvlab::test::shot(2 * i + 1)) << i;
    EXPECT_TRUE(at_join[i] == curvlab::test::shot(2 * i)) << i;
  }
  const auto poses = host.all<net::PoseFrame>();
  ASSERT_FALSE(poses.empty());
  for (std::size_t i = 1; i < poses.size(); ++i) EXPECT_GT(poses[i].sequence, poses[i - 1].sequence);
  const auto c = host.link.counters();
  EXPECT_EQ(c.poses_received, poses.size());
  EXPECT_LE(c.poses_received + c.poses_lost, sent_poses);
  EXPECT_EQ(c.dropped.total(), 0u);
  EXPECT_GT(relay->counters().dropped, 0u);

  const auto at_host_clock = host.link.clock();  // the joiner's clock minus the host's
  EXPECT_LE(std::llabs(at_host_clock.offset_ns - true_offset), at_host_clock.uncertainty_ns + 2)
      << "estimate " << at_host_clock.offset_ns << " round trip " << at_host_clock.round_trip_ns;
  EXPECT_GE(at_host_clock.round_trip_ns, 100'000'000);  // the relay's 2 × 50 ms are in it
  const auto at_join_clock = join.link.clock();
  EXPECT_LE(std::llabs(at_join_clock.offset_ns + true_offset), at_join_clock.uncertainty_ns + 2);
}
