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

#include <atomic>
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
  std::int64_t wait_ns = 60'000'000'000;  // for the partner to appear
};

struct SharedPlay {
  SharedOptions options;
  std::optional<net::Link> link;
  net::Hello mine, partner;
  net::Uuid game_uuid{};
  std::uint32_t partner_completed_shots = 0;  // as the partner's game state said at connection
  std::string software_version;
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

}  // namespace curvlab::harness::runner
