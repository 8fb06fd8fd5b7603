// A seeded UDP relay on the loopback for the shared-play tests and bench
// (docs/shared_play.md, "Tests"): this machine's kernel has no netem qdisc,
// so loss, delay and reordering are made here, between the joiner and the
// host. The joiner sends to the relay's port; the relay forwards to the
// host's port, and the host's answers back to the joiner (the latest address
// the relay heard the joiner from, so a restarted joiner is relayed too).
//
// Each datagram, in each direction: dropped with probability `loss`;
// otherwise held delay + U(0, jitter), and with probability `reorder` a
// further 2·jitter + 5 ms, so that it arrives after datagrams sent later.
// The decisions come from one std::mt19937_64 seeded with `seed`, in the
// order the datagrams arrive.
//
// Linux only (POSIX sockets). Ownership: the relay owns its two sockets and
// its thread; the destructor stops the thread and closes them. counters()
// may be called from any thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

namespace curvlab::test {

struct RelayOptions {
  std::uint16_t listen_port = 0;  // 0: any free port (port() says which)
  std::uint16_t target_port = 0;  // the host's, on 127.0.0.1
  double loss = 0.0;
  std::int64_t delay_ns = 0;
  std::int64_t extra_delay_to_joiner_ns = 0;  // an asymmetric path: added host → joiner only
  std::int64_t jitter_ns = 0;
  double reorder = 0.0;
  std::uint64_t seed = 1;
};

struct RelayCounters {
  std::uint64_t forwarded = 0, dropped = 0, reordered = 0;
};

class UdpRelay {
 public:
  // Empty with `error` set when a socket cannot be opened.
  static std::unique_ptr<UdpRelay> start(const RelayOptions& options, std::string* error);
  ~UdpRelay();
  UdpRelay(const UdpRelay&) = delete;
  UdpRelay& operator=(const UdpRelay&) = delete;

  [[nodiscard]] std::uint16_t port() const { return port_; }
  [[nodiscard]] RelayCounters counters() const;

 private:
  UdpRelay() = default;
  void run();

  RelayOptions options_;
  int front_ = -1;  // bound to 127.0.0.1:port_, talks with the joiner
  int back_ = -1;   // connected to 127.0.0.1:target_port
  std::uint16_t port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> forwarded_{0}, dropped_{0}, reordered_{0};
  std::thread thread_;
};

}  // namespace curvlab::test
