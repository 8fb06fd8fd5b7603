// Shared play's link on the loopback (docs/shared_play.md, "How well"):
//   1. partner-pose latency, sent → drawn: one station sends its head, hands
//      and cue every 90 Hz frame; the other draws at 90 Hz (half a frame out
//      of step) from its PartnerPoseBuffer at the frame's time, and each pose
//      frame's latency is the time of the first drawn frame whose newest
//      sample it is minus the time it was sent; directly, and through the
//      seeded UDP relay without and with 50 ms delay and 5% loss;
//   2. the bytes per second each way (curvlab's messages, and UDP payloads
//      with ENet's headers, acknowledgements and clock pings);
//   3. the clock estimate against the true offset: 0 on one machine, and
//      with offsets injected into the joiner's clock, directly and through
//      symmetric and asymmetric relays.
//
//   build/ci/bin/bench_net_link [seconds per case]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <curvlab/geometry/isometry.hpp>
#include <curvlab/harness/net/link.hpp>
#include <curvlab/harness/net/partner_poses.hpp>

#include "offset_clock.hpp"
#include "udp_relay.hpp"

namespace net = curvlab::harness::net;
using namespace curvlab::geometry;

namespace {

constexpr std::int64_t kFrameNs = 11'111'111;

struct Path {
  const char* name;
  bool relay;
  curvlab::test::RelayOptions options;
};

struct Pair {
  std::unique_ptr<curvlab::test::UdpRelay> relay;
  std::optional<net::Link> host, join;
};

Pair connect(const Path& path, const curvlab::harness::io::Clock& host_clock,
             const curvlab::harness::io::Clock& join_clock, net::LinkOptions options) {
  Pair p;
  auto h = net::Link::listen("127.0.0.1", 0, host_clock, options);
  if (!h) {
    std::fprintf(stderr, "bench_net_link: %s\n", h.error().message.c_str());
    std::exit(1);
  }
  p.host.emplace(std::move(h).value());
  std::uint16_t port = p.host->port();
  if (path.relay) {
    auto o = path.options;
    o.target_port = port;
    std::string error;
    p.relay = curvlab::test::UdpRelay::start(o, &error);
    if (!p.relay) {
      std::fprintf(stderr, "bench_net_link: %s\n", error.c_str());
      std::exit(1);
    }
    port = p.relay->port();
  }
  auto j = net::Link::join("127.0.0.1", port, join_clock, options);
  if (!j) {
    std::fprintf(stderr, "bench_net_link: %s\n", j.error().message.c_str());
    std::exit(1);
  }
  p.join.emplace(std::move(j).value());
  for (int i = 0; i < 20000 && !(p.host->connected() && p.join->connected()); ++i) {
    (void)p.host->poll(1);
    (void)p.join->poll(1);
  }
  if (!(p.host->connected() && p.join->connected())) {
    std::fprintf(stderr, "bench_net_link: the stations did not connect on %s\n", path.name);
    std::exit(1);
  }
  return p;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

net::PoseFrame pose_at(std::uint32_t seq, std::int64_t t_ns) {
  const Space space{SpaceKind::S3, 0.8};
  const double t = 1e-9 * static_cast<double>(t_ns);
  net::PoseFrame f;
  f.sequence = seq;
  f.display_ns = t_ns;
  f.space = space.kind;
  f.radius_m = space.radius_m;
  f.tracked = 0b1111;
  f.pose[0] = translation_m(space, {0.1 * std::sin(t), 1.6, 0.5}) * rotation(Vec3{0.0, 1.0, 0.0}, 0.2 * t);
  f.pose[1] = translation_m(space, {-0.2, 1.0, 0.2 + 0.1 * std::cos(t)});
  f.pose[2] = translation_m(space, {0.2, 1.0, 0.2});
  f.pose[3] = translation_m(space, {0.2, 0.9, -0.2}) * rotation(Vec3{1.0, 0.0, 0.0}, -1.4);
  return f;
}

void latency_case(const Path& path, double seconds) {
  const curvlab::harness::io::SteadyClock clock;
  Pair p = connect(path, clock, clock, {});
  net::PartnerPoseBuffer buffer;
  std::vector<std::int64_t> sent_ns;  // by sequence
  std::vector<double> network_ms, drawn_ms;
  std::uint32_t last_drawn = 0;
  const std::int64_t start = clock.now_ns();
  const std::int64_t end = start + static_cast<std::int64_t>(seconds * 1e9);
  std::int64_t next_send = start, next_draw = start + kFrameNs / 2, next_shot = start;
  std::uint32_t seq = 0, shots = 0;
  const auto before_host = p.host->counters();
  const auto before_join = p.join->counters();
  while (clock.now_ns() < end) {
    const std::int64_t now = clock.now_ns();
    if (now >= next_send) {
      sent_ns.push_back(now);
      p.join->send(pose_at(++seq, now));
      p.join->flush();
      next_send += kFrameNs;
    }
    if (now >= next_shot) {  // a shot every two seconds, as in play
      net::Shot s;
      s.shot_index = shots++;
      s.events.resize(40);
      s.rest.resize(16);
      p.join->send(s);
      next_shot += 2'000'000'000;
    }
    for (auto& r : p.host->poll(0).messages) {
      if (auto* f = std::get_if<net::PoseFrame>(&r.message)) {
        // One machine, one clock: the partner's display time is ours.
        buffer.push(*f, f->display_ns);
        network_ms.push_back(1e-6 * static_cast<double>(r.received_ns - f->display_ns));
      }
    }
    (void)p.join->poll(0);
    if (now >= next_draw) {
      const auto drawn = buffer.at(now);
      if (drawn.valid && drawn.newest_sequence != last_drawn) {
        last_drawn = drawn.newest_sequence;
        drawn_ms.push_back(1e-6 * static_cast<double>(now - sent_ns[drawn.newest_sequence - 1]));
      }
      next_draw += kFrameNs;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  const double d = 1e-9 * static_cast<double>(clock.now_ns() - start);
  const auto h = p.host->counters();
  const auto j = p.join->counters();
  std::printf("%-30s %6u %6zu %8.2f %8.2f %8.2f %8.2f %8.2f %9.0f %9.0f %9.0f\n", path.name, seq, drawn_ms.size(),
              percentile(network_ms, 0.5), percentile(drawn_ms, 0.5), percentile(drawn_ms, 0.95),
              drawn_ms.empty() ? 0.0 : *std::max_element(drawn_ms.begin(), drawn_ms.end()),
              100.0 * static_cast<double>(h.poses_lost) / std::max(1.0, static_cast<double>(seq)),
              static_cast<double>(j.bytes_sent - before_join.bytes_sent) / d,
              static_cast<double>(j.wire_bytes_sent - before_join.wire_bytes_sent) / d,
              static_cast<double>(h.wire_bytes_sent - before_host.wire_bytes_sent) / d);
}

void clock_case(const char* name, std::int64_t true_offset_ns, const Path& path, double seconds) {
  const curvlab::harness::io::SteadyClock host_clock;
  const curvlab::test::OffsetClock join_clock(true_offset_ns);
  net::LinkOptions options;
  options.ping_interval_ns = 100'000'000;
  Pair p = connect(path, host_clock, join_clock, options);
  const std::int64_t end = host_clock.now_ns() + static_cast<std::int64_t>(seconds * 1e9);
  while (host_clock.now_ns() < end) {
    (void)p.host->poll(1);
    (void)p.join->poll(1);
  }
  const auto e = p.host->clock();
  std::printf("%-46s %14.3f %14.3f %10.3f %10.3f %8zu\n", name, 1e-6 * static_cast<double>(true_offset_ns),
              1e-6 * static_cast<double>(e.offset_ns), 1e-6 * static_cast<double>(e.offset_ns - true_offset_ns),
              1e-6 * static_cast<double>(e.uncertainty_ns), e.samples);
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 4.0;
  if (!net::built_with_enet()) {
    std::printf("bench_net_link: %s\n", net::enet_description().c_str());
    return 0;
  }
  std::printf("Shared-play link on the loopback (%s), %.1f s per case, poses at 90 Hz, a shot every 2 s\n\n",
              net::enet_description().c_str(), seconds);
  std::printf("1-2. Partner-pose latency (ms) and bytes/s\n");
  std::printf("%-30s %6s %6s %8s %8s %8s %8s %8s %9s %9s %9s\n", "path", "sent", "drawn", "net p50", "drawn p50",
              "drawn p95", "max", "lost %", "msg B/s", "udp B/s", "back B/s");
  const Path direct{"direct", false, {}};
  const Path relay0{"relay, no loss or delay", true, {}};
  const Path relay50{"relay, 50 ms, 5% loss, 5 ms jit", true,
                     {.loss = 0.05, .delay_ns = 50'000'000, .jitter_ns = 5'000'000, .reorder = 0.01, .seed = 1}};
  for (const Path* path : {&direct, &relay0, &relay50}) latency_case(*path, seconds);
  std::printf("(net: received − sent; drawn: the first 90 Hz frame drawing it − sent; msg: curvlab's messages "
              "sender → partner; udp: with ENet's headers and pings; back: partner → sender, acks and pongs)\n\n");

  std::printf("3. Clock offset estimate (the joiner's clock minus the host's, ms)\n");
  std::printf("%-46s %14s %14s %10s %10s %8s\n", "case", "true", "estimate", "error", "+/- bound", "samples");
  const Path asym{"", true, {.delay_ns = 20'000'000, .extra_delay_to_joiner_ns = 20'000'000, .seed = 3}};
  const Path sym{"", true, {.loss = 0.05, .delay_ns = 50'000'000, .jitter_ns = 5'000'000, .seed = 2}};
  clock_case("one machine, direct", 0, direct, seconds);
  clock_case("offset +1.5 s, direct", 1'500'000'000, direct, seconds);
  clock_case("offset -250 ms, direct", -250'000'000, direct, seconds);
  clock_case("offset +1.5 s, relay 50 ms each way, 5% loss", 1'500'000'000, sym, seconds);
  clock_case("offset +1.5 s, relay 20 ms to host, 40 to joiner", 1'500'000'000, asym, seconds);
  std::printf("(bound: half the round trip of the exchange used; an asymmetric path shifts the estimate by half "
              "the difference, +10 ms in the last case)\n");
  return 0;
}
