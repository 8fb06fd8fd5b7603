// Shared play (docs/shared_play.md): two stations, each its own session at
// its own physical table, play one game on one curved table. The command
// line connects the stations and compares them (connect_partner) before
// either writes a session; the play block then takes turns over the link:
// the shooter's station simulates its shot and sends the strike's inputs,
// events and rest state; the other simulates the same inputs again, compares,
// and keeps the shooter's rest state.
//
// Ownership: SharedPlay owns the link; the caller owns the SharedPlay and
// keeps it alive for the whole run (RunOptions::shared points at it). Used by
// the session's frame thread only.
#pragma once

#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/net/handshake.hpp"
#include "curvlab/harness/net/link.hpp"
#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/result.hpp"
#include "curvlab/renderer/text.hpp"

#include <atomic>
#include <mutex>
#include <thread>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

namespace curvlab::harness::runner {

struct SharedOptions {
  net::Role role = net::Role::host;
  std::string partner_host;        // join: the host's address
  std::uint16_t port = 0;          // host: the port it listens on; join: the host's
  std::string bind_address = "0.0.0.0";
  std::string initials;            // drawn on this station's avatar at the partner's
  std::optional<net::Avatar> avatar;  // this player's photo, drawn there instead (avatar_from_png)
  std::int64_t wait_ns = 60'000'000'000;  // for the partner to appear
};

// The link between the stations for the whole session. Once started, a
// service thread waits on the link's socket and polls it the moment a
// datagram arrives — so clock pings are answered and stamped then, not at
// the next frame — and keeps what arrived for the frame thread's take().
// Every call on the link holds one mutex; the messages kept are bounded
// (pose frames beyond 256 waiting drop the oldest).
class SharedPlay {
 public:
  SharedOptions options;
  std::optional<net::Link> link;  // used directly only before start_service()
  net::Hello mine, partner;
  net::Uuid game_uuid{};
  std::uint32_t partner_completed_shots = 0;  // as the partner's game state said at connection
  std::optional<net::Avatar> partner_avatar;  // the partner's photo, when it sent one
  std::string software_version;

  SharedPlay() = default;
  SharedPlay(const SharedPlay&) = delete;
  SharedPlay& operator=(const SharedPlay&) = delete;
  ~SharedPlay();

  void start_service();
  void stop_service();
  // What arrived since the last take, with the connection changes.
  net::Poll take();
  bool send(const net::Message& m);
  void flush();
  bool connected();
  void reconnect();
  net::ClockEstimate clock();
  std::int64_t to_local_ns(std::int64_t partner_ns);
  net::LinkCounters counters();
  // Stops the service and says goodbye.
  void close(const net::Bye& bye, int timeout_ms);

 private:
  void serve();
  std::mutex mutex_;
  net::Poll inbox_;
  std::size_t poses_waiting_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// The parameters the two stations must share beyond the protocol file: each
// play block's game (shots, duration, rack, physics) and the table.
net::Parameters shared_parameters(const protocol::Protocol& p);

// Listens or joins, waits for the partner (at most options.wait_ns), swaps
// hellos and compares them; the host then names the game (a new UUID) and
// the joiner learns it. An Error — usage (exit 2) naming every difference,
// or device (exit 1) when no partner came — leaves nothing written.
Result<std::unique_ptr<SharedPlay>> connect_partner(const SharedOptions& options, const protocol::Protocol& p,
                                                    const std::string& protocol_text, const io::Clock& clock,
                                                    const std::atomic<int>* stop_signal);

std::string uuid_text(const net::Uuid& u);

// A player's photo for the partner's avatar: a PNG in grey levels, scaled
// down by whole-pixel averages to fit kMaxAvatarSide (aspect kept), any
// transparency on white. An Error (usage) names the file and what is wrong.
Result<net::Avatar> avatar_from_png(const std::string& path);

// The face the partner's avatar shows: its photo, or else its initials
// ("?" when it has none), as ink coverage for a panel (0 paper, 255 ink;
// panels draw light ink on dark paper, so a photo's coverage is its grey).
// An Error (device) when the font cannot be read.
Result<renderer::CoverageBitmap> avatar_face(const std::optional<net::Avatar>& photo, const std::string& initials,
                                             const std::string& font);

}  // namespace curvlab::harness::runner
