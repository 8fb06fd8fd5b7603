// curvlab_udp_relay: the seeded UDP relay (tests/support/udp_relay.hpp) as a
// program, for trying two stations on one machine under loss and delay:
//
//   curvlab_udp_relay --target 7777 [--listen 7778] [--loss 0.05] [--delay-ms 50]
//                     [--jitter-ms 5] [--reorder 0.01] [--seed 1]
//
// It prints the port it listens on (one line) and relays until stdin closes
// or it is sent SIGINT/SIGTERM, then prints what it forwarded and dropped.
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

#include <poll.h>
#include <unistd.h>

#include "udp_relay.hpp"

namespace {
volatile std::sig_atomic_t stop = 0;
void on_signal(int) { stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  curvlab::test::RelayOptions o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(stderr, "curvlab_udp_relay: %s needs a value\n", a.c_str());
      return 2;
    }
    const char* v = argv[++i];
    if (a == "--target") o.target_port = static_cast<std::uint16_t>(std::atoi(v));
    else if (a == "--listen") o.listen_port = static_cast<std::uint16_t>(std::atoi(v));
    else if (a == "--loss") o.loss = std::atof(v);
    else if (a == "--delay-ms") o.delay_ns = static_cast<std::int64_t>(std::atof(v) * 1e6);
    else if (a == "--jitter-ms") o.jitter_ns = static_cast<std::int64_t>(std::atof(v) * 1e6);
    else if (a == "--reorder") o.reorder = std::atof(v);
    else if (a == "--seed") o.seed = std::strtoull(v, nullptr, 10);
    else {
      std::fprintf(stderr, "curvlab_udp_relay: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (o.target_port == 0) {
    std::fprintf(stderr, "curvlab_udp_relay: --target PORT is required\n");
    return 2;
  }
  std::string error;
  auto relay = curvlab::test::UdpRelay::start(o, &error);
  if (!relay) {
    std::fprintf(stderr, "curvlab_udp_relay: %s\n", error.c_str());
    return 1;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::printf("%u\n", relay->port());
  std::fflush(stdout);
  while (!stop) {
    pollfd in{0, POLLIN, 0};
    if (::poll(&in, 1, 100) > 0) {
      char buf[256];
      if (::read(0, buf, sizeof buf) <= 0) break;
    }
  }
  const auto c = relay->counters();
  std::fprintf(stderr, "curvlab_udp_relay: forwarded %llu, dropped %llu, reordered %llu\n",
               static_cast<unsigned long long>(c.forwarded), static_cast<unsigned long long>(c.dropped),
               static_cast<unsigned long long>(c.reordered));
  return 0;
}
