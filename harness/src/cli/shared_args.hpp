// `run --shared host|join` (docs/shared_play.md): the options that link this
// station to its partner, and the link itself, connected and compared before
// the session is written.
#pragma once

#include "common.hpp"
#include "station.hpp"

#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/runner/shared_play.hpp"

#include <CLI/CLI.hpp>

#include <atomic>
#include <memory>
#include <string>

namespace curvlab::harness::cli {

struct SharedArgs {
  std::string role;      // --shared: "" (alone), host or join
  std::string listen;    // --listen PORT (host)
  std::string partner;   // --partner HOST:PORT (join)
  std::string bind = "0.0.0.0";
  std::string initials;  // --initials (default: the participant's first two characters)
  double wait_s = 60.0;  // --partner-wait-s
  std::string avatar;    // --avatar FILE.png (default: the initials)
};

void add_shared_options(CLI::App* cmd, SharedArgs& a);

// Checked before any device opens: a build without ENet, a missing port or
// address, a fast headless run or a protocol without a play block is a usage
// error (exit 2).
void check_shared_args(const SharedArgs& a, const harness::protocol::Protocol& p, const BackendArgs& backend);

// Connects and compares (runner::connect_partner); null when --shared is not given.
std::unique_ptr<harness::runner::SharedPlay> open_shared(const SharedArgs& a, const std::string& participant,
                                                         const harness::protocol::Protocol& p,
                                                         const std::string& protocol_text,
                                                         const harness::io::Clock& clock,
                                                         const std::atomic<int>* stop_signal);

// Says goodbye to the partner after the session: the game is over when the
// session completed, paused (the partner waits) when it was interrupted.
void close_shared(harness::runner::SharedPlay* shared, bool completed);

}  // namespace curvlab::harness::cli
