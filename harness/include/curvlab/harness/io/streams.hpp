// What a session tells a lab's other instruments while it runs (DESIGN.md
// §6; docs/lsl.md): markers of what happened, each stamped with the moment
// it describes on the session clock, and each frame's poses and gaze at
// the frame's predicted display time. The Lab Streaming Layer's outlets
// (lsl/session_streams.hpp) are the implementation; a session with none
// (RunOptions::streams null) streams nothing.
//
// Thread-safety: start(), marker() and frame() are called from the frame
// thread only, and must return at once: an implementation hands the work to
// a thread of its own and never blocks the frame.
#pragma once

#include "curvlab/geometry/tracking.hpp"
#include "curvlab/harness/io/gaze.hpp"
#include "curvlab/harness/result.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace curvlab::harness::io {

// The session the streams belong to, known once it is stored.
struct StreamedSession {
  std::string db_path;
  std::int64_t session_id = 0;
  double refresh_hz = 90.0;  // the display's: the poses' nominal rate
};

class SessionStreams {
 public:
  virtual ~SessionStreams() = default;
  SessionStreams() = default;
  SessionStreams(const SessionStreams&) = delete;
  SessionStreams& operator=(const SessionStreams&) = delete;

  // Before the session's first frame (and again for a resumed run of the
  // same session): the streams open, named after the session.
  virtual Result<Done> start(const StreamedSession& session) = 0;
  // `text` happened at `t_ns` (session clock).
  virtual void marker(std::int64_t t_ns, std::string text) = 0;
  // The frame shown at `display_ns` (session clock) and the poses and gaze
  // located for it.
  virtual void frame(std::int64_t display_ns, const geometry::LabFrame& lab, const std::optional<Gaze>& gaze) = 0;
};

}  // namespace curvlab::harness::io
