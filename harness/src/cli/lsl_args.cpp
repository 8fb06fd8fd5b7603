#include "lsl_args.hpp"

#include "curvlab/harness/lsl/session_streams.hpp"

#include <chrono>
#include <cmath>

namespace curvlab::harness::cli {

void add_lsl_options(CLI::App* cmd, LslArgs& a) {
  cmd->add_flag("--lsl", a.outlets,
                "stream markers, poses and gaze to the Lab Streaming Layer (also the protocol's [lsl] outlets; "
                "docs/lsl.md)");
  cmd->add_option("--lsl-record", a.record,
                  "record another instrument's LSL stream, found by its name or type, into the session "
                  "(repeatable)");
  cmd->add_option("--lsl-wait-s", a.wait_s,
                  "with --lsl: wait up to this many seconds for a recorder (LabRecorder) to connect before the "
                  "first page (default 0)");
}

namespace {

bool streams_wanted(const LslArgs& a, const harness::protocol::Protocol& p) {
  return a.outlets || p.lsl_outlets || !a.record.empty();
}

}  // namespace

void check_lsl_args(const LslArgs& a, const harness::protocol::Protocol& p, const BackendArgs& backend) {
  if (!(a.wait_s >= 0.0 && a.wait_s <= 3600.0)) throw UsageError("--lsl-wait-s must lie in [0, 3600] seconds");
  if (!streams_wanted(a, p)) return;
  const std::string asked = a.outlets ? "--lsl" : !a.record.empty() ? "--lsl-record" : p.file + ": [lsl] outlets";
  if (!lsl::available()) throw UsageError(asked + ": " + lsl::unavailable_message());
  // The LSL clock is the machine's: simulated time has no place on it.
  if (backend.backend == "headless" && backend.pace == "fast")
    throw UsageError(asked + " needs a session in real time: add --pace realtime (a fast headless run's clock is "
                             "simulated)");
}

std::unique_ptr<harness::io::SessionStreams> open_lsl(const LslArgs& a, const harness::protocol::Protocol& p,
                                                      const harness::io::Clock& clock) {
  if (!streams_wanted(a, p)) return nullptr;
  lsl::StreamOptions o;
  o.outlets = a.outlets || p.lsl_outlets;
  o.record = a.record;
  o.wait_for_recorder = std::chrono::milliseconds(std::llround(a.wait_s * 1000.0));
  auto opened = lsl::open(o, clock);
  if (!opened) raise(opened.error());
  return std::move(opened).value();
}

std::string lsl_build_line() {
  return lsl::available() ? "with Lab Streaming Layer (liblsl " + lsl::library_version() + ")"
                          : "without Lab Streaming Layer (liblsl was not found when curvlab was built; docs/lsl.md)";
}

}  // namespace curvlab::harness::cli
