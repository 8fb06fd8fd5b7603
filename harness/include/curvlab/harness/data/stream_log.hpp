// The Lab Streaming Layer's rows (data_schema/codebook.md, "lsl_streams",
// "lsl_samples", "lsl_clock"): the streams a session sends and records, the
// recorded samples on the session clock, and the measured mapping between
// the session clock and the LSL clock (docs/lsl.md).
//
// Written beside the session's own writer, from threads other than the
// frame thread (the LSL recorder's and clock's), through a connection of
// its own; each call commits its own transaction. Thread-safety: every
// member may be called from any thread (one mutex guards the connection).
// Not copyable or movable.
#pragma once

#include "curvlab/harness/data/error.hpp"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace curvlab::harness::data {

enum class LslRole { outlet, recorded };
std::string_view to_string(LslRole role);

struct LslStreamRecord {
  std::int64_t session_id = 0;
  LslRole role = LslRole::outlet;
  std::string name;
  std::string type;
  std::string source_id;
  int channel_count = 1;
  double nominal_srate_hz = 0.0;  // 0: irregular
  std::string channel_format;     // float32, string, …
  std::string info_xml;           // the stream's full description as LSL gives it
};

struct LslSampleRecord {
  std::int64_t lsl_stream_id = 0;
  std::int64_t t_ns = 0;       // session clock: the sample's LSL time mapped
  double lsl_time_s = 0.0;     // its time stamp as sent, on the sender's LSL clock
  double lsl_offset_s = 0.0;   // the sender's clock offset measured then (add to lsl_time_s)
  std::int64_t received_ns = 0;  // session clock when it arrived
  std::string value_json;      // its channels, a JSON array
};

struct LslClockRecord {
  std::int64_t session_id = 0;
  std::int64_t t_ns = 0;         // session clock
  double lsl_time_s = 0.0;       // lsl_local_clock() at that moment
  std::int64_t uncertainty_ns = 0;  // half the time the reading took
};

class StreamLog {
 public:
  // Opens an existing data file (the session's) for writing.
  static Expected<std::unique_ptr<StreamLog>> open(const std::string& path);
  ~StreamLog();
  StreamLog(const StreamLog&) = delete;
  StreamLog& operator=(const StreamLog&) = delete;

  // The session's UUID (sessions.session_uuid); not_found when it has none.
  Expected<std::string> session_uuid(std::int64_t session_id);
  // The stream's row; a resumed session's stream with the same role, source
  // id, name and type keeps the row it had.
  Expected<std::int64_t> add_stream(const LslStreamRecord& r);
  Expected<Done> add_clock(const LslClockRecord& r);
  // All in one transaction.
  Expected<Done> add_samples(const std::vector<LslSampleRecord>& samples);

 private:
  struct Impl;
  explicit StreamLog(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace curvlab::harness::data
