// One station's connection to its partner (docs/shared_play.md): ENet over
// UDP, three channels —
//   0  unreliable, sequenced: pose frames (a late one is dropped, never
//      drawn after a newer one);
//   1  reliable, ordered: hello, shot, game state, bye;
//   2  unsequenced: clock ping and pong (answered as soon as they arrive,
//      so a retransmission never stretches a round trip).
// The host listens on a port and accepts one partner at a time (a partner
// that comes back after a kill replaces the stale one); the joiner connects
// and connects again after a disconnect when asked. Every datagram is
// decoded by messages.hpp; one that fails is dropped and counted. The link
// answers pings, pings every ping_interval_ns itself, and keeps the clock
// estimate (clock_sync.hpp).
//
// ENet is optional at build time (CURVLAB_WITH_ENET, like LSL): without it
// listen() and join() return an Error saying that shared play is not built
// in, and built_with_enet() is false.
//
// Ownership and threads: a Link owns its ENet host (destroyed with it) and is
// move-only; it is used by one thread at a time. The clock it is given must
// outlive it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <curvlab/harness/io/clock.hpp>
#include <curvlab/harness/net/clock_sync.hpp>
#include <curvlab/harness/net/messages.hpp>
#include <curvlab/harness/result.hpp>

namespace curvlab::harness::net {

bool built_with_enet();
// "ENet 1.3.17", or why there is none.
std::string enet_description();

struct LinkOptions {
  std::int64_t ping_interval_ns = 250'000'000;
  std::size_t clock_window = 32;
  // ENet declares a peer gone when nothing is acknowledged for this long.
  std::uint32_t timeout_ms = 3000;
};

// What crossed the link so far.
struct LinkCounters {
  std::uint64_t datagrams_sent = 0, datagrams_received = 0;
  std::uint64_t bytes_sent = 0, bytes_received = 0;  // curvlab's messages, without UDP/ENet headers
  std::uint64_t wire_bytes_sent = 0, wire_bytes_received = 0;  // UDP payloads: with ENet's headers, acks, pings
  std::uint64_t poses_received = 0;
  std::uint64_t poses_late = 0;   // older than one already received (dropped)
  std::uint64_t poses_lost = 0;   // sequence numbers never seen
  DropCounters dropped;           // malformed or oversized (dropped)
  std::uint32_t enet_rtt_ms = 0;  // ENet's mean round trip of reliable packets
  double enet_loss = 0.0;         // ENet's mean loss of reliable packets, 0–1
  std::uint64_t connects = 0, disconnects = 0;
};

struct Received {
  Message message;
  std::int64_t received_ns = 0;  // this station's clock
};

struct Poll {
  std::vector<Received> messages;  // in arrival order; pings and pongs are handled inside
  bool connected = false;          // a partner connected during this poll
  bool disconnected = false;       // the partner left or timed out during this poll
};

class Link {
 public:
  // The host: listens on bind_address:port (port 0: any free port; port()
  // says which).
  static Result<Link> listen(const std::string& bind_address, std::uint16_t port, const io::Clock& clock,
                             LinkOptions options = {});
  // The joiner: starts connecting to host:port; poll() reports the connection.
  static Result<Link> join(const std::string& host, std::uint16_t port, const io::Clock& clock,
                           LinkOptions options = {});
  // "HOST:PORT" (IPv4 address or name); an Error naming what is wrong otherwise.
  static Result<std::pair<std::string, std::uint16_t>> parse_address(const std::string& text);

  Link(Link&&) noexcept;
  Link& operator=(Link&&) noexcept;
  ~Link();

  [[nodiscard]] bool connected() const;
  [[nodiscard]] std::uint16_t port() const;
  // The joiner connects again (after a disconnect); a no-op on the host.
  void reconnect();
  // Queued; sent by the next poll() or flush(). False when no partner is
  // connected (nothing is queued then).
  bool send(const Message& m);
  void flush();
  // Services the network, waiting up to timeout_ms for the first event.
  Poll poll(int timeout_ms);
  // Waits up to timeout_ms until a datagram can be read, touching no ENet
  // state (only the socket): a service thread may call it without the lock
  // under which it calls everything else.
  void wait_readable(int timeout_ms) const;
  // Sends a Bye and waits up to timeout_ms for it to be acknowledged.
  void close(const Bye& bye, int timeout_ms);

  [[nodiscard]] LinkCounters counters() const;
  [[nodiscard]] ClockEstimate clock() const;
  [[nodiscard]] const ClockEstimator& clock_estimator() const;

 private:
  struct Impl;
  explicit Link(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace curvlab::harness::net
