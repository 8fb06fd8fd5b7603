#include "curvlab/harness/data/stream_log.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/sqlite.hpp"

#include <mutex>

namespace curvlab::harness::data {

std::string_view to_string(LslRole role) {
  switch (role) {
    case LslRole::outlet: return "outlet";
    case LslRole::recorded: return "recorded";
  }
  return "outlet";
}

struct StreamLog::Impl {
  explicit Impl(Database database)
      : db(std::move(database)),
        find_stream(db.connection(),
                    "SELECT lsl_stream_id FROM lsl_streams WHERE session_id = ?1 AND role = ?2 AND source_id = ?3 "
                    "AND name = ?4 AND type = ?5"),
        insert_stream(db.connection(),
                      "INSERT INTO lsl_streams (session_id, role, name, type, source_id, channel_count, "
                      "nominal_srate_hz, channel_format, info_xml) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)"),
        insert_clock(db.connection(),
                     "INSERT INTO lsl_clock (session_id, t_ns, lsl_time_s, uncertainty_ns) VALUES (?1, ?2, ?3, ?4)"),
        insert_sample(db.connection(),
                      "INSERT INTO lsl_samples (lsl_stream_id, t_ns, lsl_time_s, lsl_offset_s, received_ns, value) "
                      "VALUES (?1, ?2, ?3, ?4, ?5, ?6)"),
        uuid(db.connection(), "SELECT session_uuid FROM sessions WHERE session_id = ?1") {}

  template <class F>
  auto guarded(F&& body) -> decltype(body()) {
    std::lock_guard lock(mutex);
    try {
      return body();
    } catch (const SqliteFailure& failure) {
      return to_data_error(failure, db.path());
    }
  }

  std::mutex mutex;
  Database db;
  Statement find_stream;
  Statement insert_stream;
  Statement insert_clock;
  Statement insert_sample;
  Statement uuid;
};

Expected<std::unique_ptr<StreamLog>> StreamLog::open(const std::string& path) {
  auto db = Database::open(path, OpenMode::open_existing);
  if (!db) return db.error();
  try {
    return std::unique_ptr<StreamLog>(new StreamLog(std::make_unique<Impl>(std::move(db).value())));
  } catch (const SqliteFailure& failure) {
    return to_data_error(failure, path);
  }
}

StreamLog::StreamLog(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
StreamLog::~StreamLog() = default;

Expected<std::string> StreamLog::session_uuid(std::int64_t session_id) {
  return impl_->guarded([&]() -> Expected<std::string> {
    auto& s = impl_->uuid;
    s.reset();
    s.bind(1, session_id);
    if (!s.step() || s.is_null(0))
      return DataError{DataError::Kind::not_found, "session " + std::to_string(session_id) + " has no UUID"};
    std::string text = s.column_text(0);
    s.reset();
    return text;
  });
}

Expected<std::int64_t> StreamLog::add_stream(const LslStreamRecord& r) {
  return impl_->guarded([&]() -> Expected<std::int64_t> {
    Transaction txn(impl_->db.connection());
    auto& f = impl_->find_stream;
    f.reset();
    f.bind(1, r.session_id).bind(2, to_string(r.role)).bind(3, std::string_view(r.source_id));
    f.bind(4, std::string_view(r.name)).bind(5, std::string_view(r.type));
    if (f.step()) {
      const std::int64_t id = f.column_int(0);
      f.reset();
      return id;
    }
    f.reset();
    auto& s = impl_->insert_stream;
    s.bind(1, r.session_id).bind(2, to_string(r.role)).bind(3, std::string_view(r.name));
    s.bind(4, std::string_view(r.type)).bind(5, std::string_view(r.source_id)).bind(6, r.channel_count);
    s.bind(7, r.nominal_srate_hz).bind(8, std::string_view(r.channel_format)).bind(9, std::string_view(r.info_xml));
    s.run();
    const std::int64_t id = impl_->db.connection().last_insert_rowid();
    txn.commit();
    return id;
  });
}

Expected<Done> StreamLog::add_clock(const LslClockRecord& r) {
  return impl_->guarded([&]() -> Expected<Done> {
    impl_->insert_clock.bind(1, r.session_id).bind(2, r.t_ns).bind(3, r.lsl_time_s).bind(4, r.uncertainty_ns).run();
    return Done{};
  });
}

Expected<Done> StreamLog::add_samples(const std::vector<LslSampleRecord>& samples) {
  if (samples.empty()) return Done{};
  return impl_->guarded([&]() -> Expected<Done> {
    Transaction txn(impl_->db.connection());
    auto& s = impl_->insert_sample;
    for (const auto& r : samples) {
      s.bind(1, r.lsl_stream_id).bind(2, r.t_ns).bind(3, r.lsl_time_s).bind(4, r.lsl_offset_s);
      s.bind(5, r.received_ns).bind(6, std::string_view(r.value_json)).run();
    }
    txn.commit();
    return Done{};
  });
}

}  // namespace curvlab::harness::data
