// The Lab Streaming Layer (LSL; docs/lsl.md): a session's outlets —
// markers, poses and gaze (io/streams.hpp) — and the other instruments'
// streams it records into the session (`curvlab run --lsl-record`), all on
// one time base: the mapping between the session clock and the LSL clock is
// measured at start and every few seconds and stored (lsl_clock).
//
// liblsl is optional at build time: without it, available() is false and
// open() returns a usage error saying so.
//
// Source ids derive from the session's UUID ("curvlab-<uuid>-markers", …),
// so a recorder such as LabRecorder finds a resumed session's streams
// again.
#pragma once

#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/io/streams.hpp"
#include "curvlab/harness/result.hpp"

#include <chrono>
#include <memory>
#include <string>
#include <vector>

namespace curvlab::harness::lsl {

// Whether this build has liblsl; its version ("1.16.2 …") or "".
bool available();
std::string library_version();
// Why --lsl cannot be used here, and how to get it.
std::string unavailable_message();

struct StreamOptions {
  bool outlets = true;               // send markers, poses and gaze
  std::vector<std::string> record;   // streams to record, by name or type
  // How long to look for each recorded stream before giving up.
  std::chrono::milliseconds resolve_timeout{5000};
  // After the outlets open: how long to wait for a recorder (LabRecorder, a
  // test's inlet) to connect to the markers and poses before the first page.
  std::chrono::milliseconds wait_for_recorder{0};
  // How often the clock mapping is measured again.
  std::chrono::milliseconds clock_interval{5000};
};

// Resolves the streams to record (each must be found; bad_input naming it
// otherwise) and opens their inlets, so that a session starts only with
// all of them. The outlets open at start(). `clock` outlives the result.
Result<std::unique_ptr<io::SessionStreams>> open(const StreamOptions& options, const io::Clock& clock);

}  // namespace curvlab::harness::lsl
