#include "curvlab/harness/runner/session.hpp"

#include "session_loop.hpp"
#include "simulated_participant.hpp"
#include "session_records.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/sample_writer.hpp"
#include "curvlab/harness/data/session_store.hpp"
#include "curvlab/harness/data/writer_lock.hpp"
#include "curvlab/harness/runner/stimulus.hpp"
#include "curvlab/harness/version.hpp"

namespace curvlab::harness::runner {

std::optional<FrameDrawing> parse_frame_drawing(std::string_view text) {
  if (text == "all") return FrameDrawing::all;
  if (text == "onset") return FrameDrawing::onset;
  if (text == "none") return FrameDrawing::none;
  return std::nullopt;
}

namespace {

Result<Done> check_options(const protocol::Protocol& p, const RunOptions& options, const protocol::Design& design) {
  if (auto ok = data::check_pseudonym(options.participant); !ok)
    return Error{Error::Kind::usage, "--participant: " + ok.error().message};
  if (options.participant_number < 1) return Error{Error::Kind::usage, "the participant number must be at least 1"};
  if (options.observer)
    if (auto ok = check_observer(*options.observer); !ok)
      return Error{Error::Kind::usage, "observer: " + ok.error().message};
  if (design.trials.empty()) return Error{Error::Kind::bad_input, p.file + ": the design has no trials"};
  return Done{};
}

data::SessionRecord session_record(std::int64_t protocol_id, std::int64_t participant_id, const io::DisplayInfo& info,
                                   const protocol::Design& design, const geometry::PhysicalTableFit& calibration) {
  data::SessionRecord rec;
  rec.protocol_id = protocol_id;
  rec.participant_id = participant_id;
  rec.software_version = std::string(software_version());
  rec.software_commit = std::string(git_commit());
  rec.backend = info.backend;
  rec.renderer_device = info.renderer_device;
  rec.renderer_driver = info.renderer_driver;
  rec.display_refresh_hz = info.refresh_hz;
  rec.seed = static_cast<std::int64_t>(design.seed);
  rec.table_calibration_json = calibration_json(calibration);
  return rec;
}

// The session's rows before its first frame: protocol, participant, then in
// one transaction the session with provenance, the whole plan, the start and
// observer events.
Result<data::StartedSession> create(
    data::SessionStore& store, const protocol::Protocol& p, const std::string& protocol_text,
    const RunOptions& options, const io::DisplayInfo& info, const protocol::Design& design,
    const geometry::PhysicalTableFit& calibration, const io::Clock& clock, data::WriterLock& lock) {
  auto protocol_id = store.add_protocol(p.meta.name, protocol_text, p.file);
  if (!protocol_id) return protocol_id.error();
  auto participant_id = store.add_participant({options.participant, options.ipd_m, options.dominant_eye});
  if (!participant_id) return participant_id.error();
  data::events::SessionStart start{options.participant_number, design.seed, design.protocol_seed, data::to_string(info.backend),
                                   info.msaa, design.trials.size(), std::nullopt, std::nullopt, options.warnings};
  if (!options.run_options_json.empty()) start.run_options_json = options.run_options_json;
  if (design.counterbalance_row) start.counterbalance_row = *design.counterbalance_row;
  std::vector<data::EventRecord> events{data::event_record(0, std::nullopt, clock.now_ns(), start)};
  if (!options.note.empty())
    events.push_back(data::event_record(
        0, std::nullopt, clock.now_ns(),
        data::events::OperatorActionEvent{"note", "start", clock.now_ns(), options.note}));
  if (options.observer)
    events.push_back(
        data::event_record(0, std::nullopt, clock.now_ns(), data::events::Observer{observer_json(*options.observer)}));
  return store.start_session(session_record(*protocol_id, *participant_id, info, design, calibration),
                             block_plans(p, design), events,
                             [&lock](std::int64_t session_id) { return lock.claim(session_id); });
}

}  // namespace

RunResult run_session(const protocol::Protocol& p, const std::string& protocol_text, const std::string& db_path,
                      const RunOptions& options, const io::Station& station, const io::Clock& clock) {
  protocol::Design design = protocol::expand_design(p, options.participant_number);
  if (auto ok = check_options(p, options, design); !ok) return ok.error();
  auto lock = data::WriterLock::for_sessions(db_path);
  if (!lock) return lock.error();
  auto db = data::Database::open(db_path, data::OpenMode::create_or_open);
  if (!db) return db.error();
  data::SessionStore store(std::move(db).value());
  const auto calibration = options.calibration.value_or(nominal_calibration(p.session_settings()));
  auto created = create(store, p, protocol_text, options, station.display->info(), design, calibration, clock, *lock);
  if (!created) return created.error();
  auto writer = data::SampleWriter::open(db_path);
  if (!writer) return writer.error();

  RunOptions o = options;
  o.calibration = calibration;
  auto setup = SessionSetup::of(p, std::move(design), store, *writer.value(), station, clock, std::move(o),
                                created->session_id, std::move(created->trial_ids));
  setup.lock = &lock.value();
  const auto participant = SimulatedParticipant::seat(setup);
  auto result = SessionLoop(std::move(setup)).run(ResumePoint{}, true);
  if (result) result->db_path = db_path;
  return result;
}

}  // namespace curvlab::harness::runner
