// Markers for the lab's other instruments (io/streams.hpp; docs/lsl.md):
// every stored event, the participant's answers, each trial's and block's
// end, as one JSON object each —
//   {"event": KIND, "trial_id": ID or null, "detail": {…}}
// where KIND and detail are the events row's (data_schema/codebook.md,
// "events") or, for those that are no event, "session_start" (or "resume"),
// "response", "trial_end" and "block_end". Each marker is stamped with the moment it describes: an
// onset with its predicted display time, an answer or an early press with
// its input's time, a page with the display time of its first frame.
#include "session_frames.hpp"
#include "session_records.hpp"

#include <type_traits>

namespace curvlab::harness::runner {

namespace {

// The moment an event describes, where it carries one of its own.
std::optional<std::int64_t> own_moment(const data::Event& e) {
  return std::visit(
      [](const auto& v) -> std::optional<std::int64_t> {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, data::events::Onset>) return v.predicted_display_ns;
        else if constexpr (std::is_same_v<T, data::events::OperatorActionEvent>) return v.t_ns;
        else if constexpr (std::is_same_v<T, data::events::EarlyInput>) return v.t_ns;
        else return std::nullopt;
      },
      e);
}

std::string marker_text(std::string_view kind, std::optional<std::int64_t> trial_id, const std::string& detail_json) {
  std::string text = R"({"event":)" + Json(kind).dump() + R"(,"trial_id":)" +
                     (trial_id ? std::to_string(*trial_id) : std::string("null")) + R"(,"detail":)";
  text += detail_json.empty() ? std::string("{}") : detail_json;
  text += '}';
  return text;
}

}  // namespace

void SessionFrames::start_streams(bool resumed) {
  if (options_.streams == nullptr) return;
  io::StreamedSession s;
  s.db_path = store.path();
  s.session_id = session_id;
  s.refresh_hz = station.display->info().refresh_hz > 0.0 ? station.display->info().refresh_hz
                                                          : static_cast<double>(protocol.refresh_hz);
  if (auto ok = options_.streams->start(s); !ok) throw Stop{ok.error()};
  marker(clock.now_ns(), resumed ? "resume" : "session_start", std::nullopt,
         Json{{"session_id", session_id}, {"protocol", protocol.meta.name}, {"participant", options_.participant},
              {"trials", design.trials.size()}}
             .dump());
}

void SessionFrames::marker(std::int64_t t_ns, std::string_view kind, std::optional<std::int64_t> trial_id,
                           const std::string& detail_json) {
  if (options_.streams == nullptr) return;
  options_.streams->marker(t_ns, marker_text(kind, trial_id, detail_json));
}

void SessionFrames::mark_event(const data::EventRecord& record, const data::Event& e,
                               std::optional<std::int64_t> moment_ns) {
  const std::int64_t t_ns = moment_ns.value_or(own_moment(e).value_or(record.t_ns));
  marker(t_ns, record.kind, record.trial_id, record.detail_json);
}

void SessionFrames::mark_response(const data::TrialResult& r) {
  if (options_.streams == nullptr) return;
  marker(r.response_ns, "response", r.trial_id,
         Json{{"response", r.response},
              {"device", r.response_device},
              {"rt_ms", static_cast<double>(r.response_ns - r.onset_ns) * 1e-6}}
             .dump());
}

void SessionFrames::mark_trial_end(std::size_t i, data::TrialStatus status, const std::string& reason) {
  if (options_.streams == nullptr) return;
  marker(clock.now_ns(), "trial_end", trial_ids[i],
         Json{{"trial_index", i}, {"status", data::to_string(status)}, {"end_reason", reason}}.dump());
}

void SessionFrames::mark_block_end(std::size_t b) {
  if (options_.streams == nullptr) return;
  marker(clock.now_ns(), "block_end", std::nullopt,
         Json{{"block", design.blocks[b].name}, {"block_index", b}}.dump());
}

}  // namespace curvlab::harness::runner
