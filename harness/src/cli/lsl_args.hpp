// `run --lsl`, `--lsl-record` and `--lsl-wait-s` (docs/lsl.md): the Lab
// Streaming Layer's options of run and resume, and the streams they open.
#pragma once

#include "common.hpp"
#include "station.hpp"

#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/io/streams.hpp"
#include "curvlab/harness/protocol/protocol.hpp"

#include <CLI/CLI.hpp>

#include <memory>
#include <string>
#include <vector>

namespace curvlab::harness::cli {

struct LslArgs {
  bool outlets = false;             // --lsl
  std::vector<std::string> record;  // --lsl-record NAME_OR_TYPE
  double wait_s = 0.0;              // --lsl-wait-s
};

void add_lsl_options(CLI::App* cmd, LslArgs& a);

// The session's streams, or null when neither the options nor the
// protocol's [lsl] outlets ask for any. Checked before any device opens: a
// build without liblsl, or a headless run in simulated time, is a usage error
// (exit 2).
void check_lsl_args(const LslArgs& a, const harness::protocol::Protocol& p, const BackendArgs& backend);
// Resolves the recorded streams (exit 1 when one is not found).
std::unique_ptr<harness::io::SessionStreams> open_lsl(const LslArgs& a, const harness::protocol::Protocol& p,
                                                      const harness::io::Clock& clock);

// One line for --version, xr-check and devices: whether this curvlab streams.
std::string lsl_build_line();

}  // namespace curvlab::harness::cli
