#include "curvlab/harness/data/sample_writer.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/session_store.hpp"
#include "curvlab/harness/data/sqlite.hpp"

#include "spsc_ring.hpp"

#include <sqlite3.h>

#include <atomic>
#include <condition_variable>
#include <cstring>
#include <ctime>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

namespace curvlab::harness::data {
namespace {

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

constexpr const char* insert_tracking_sql =
    "INSERT INTO tracking_samples (session_id, trial_id, frame_index, device, t_ns, lab_px_m, "
    "lab_py_m, lab_pz_m, lab_qx, lab_qy, lab_qz, lab_qw, position_valid, orientation_valid, "
    "virtual_pose, physical_edge, virtual_edge, laps, anchor_fraction, coherence_error_m, "
    "coherence_error_rad) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, "
    "?15, ?16, ?17, ?18, ?19, ?20, ?21)";
constexpr const char* insert_partner_sql =
    "INSERT INTO partner_samples (session_id, trial_id, frame_index, device, t_ns, virtual_pose, tracked, "
    "extrapolated, sample_age_ns, distance_m) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)";
constexpr const char* insert_frame_sql =
    "INSERT INTO frames (session_id, trial_id, frame_index, t_ns, predicted_display_ns, "
    "cpu_time_ns, gpu_time_ns, dropped_frames, views, passes, draws, triangles, eye_width_px, "
    "eye_height_px, eye_views, display_period_ns, late) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, "
    "?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17)";
constexpr const char* insert_gaze_sql =
    "INSERT INTO gaze_samples (session_id, trial_id, frame_index, t_ns, combined_valid, combined_ox_m, "
    "combined_oy_m, combined_oz_m, combined_dx, combined_dy, combined_dz, left_valid, left_confidence, "
    "left_ox_m, left_oy_m, left_oz_m, left_dx, left_dy, left_dz, right_valid, right_confidence, right_ox_m, "
    "right_oy_m, right_oz_m, right_dx, right_dy, right_dz, vergence_rad, vergence_distance_m) VALUES (?1, ?2, "
    "?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19, ?20, ?21, ?22, ?23, ?24, "
    "?25, ?26, ?27, ?28, ?29)";
constexpr const char* insert_wait_sql =
    "INSERT INTO events (session_id, trial_id, t_ns, kind, detail) VALUES (?1, NULL, 0, "
    "'logger_waited', json_object('waited_ms', ?2, 'reason', ?3))";
constexpr const char* insert_event_sql =
    "INSERT INTO events (session_id, trial_id, t_ns, kind, detail) VALUES (?1, NULL, ?2, "
    "'logger_drops', json_object('dropped_tracking', ?3, 'dropped_frames', ?4, 'dropped_gaze', ?5))";

}  // namespace

struct SampleWriter::Impl {
  Impl(Connection c, SessionStore s, SampleWriterConfig cfg)
      : config(cfg),
        tracking(cfg.tracking_capacity),
        frames(cfg.frame_capacity),
        gaze(cfg.gaze_capacity),
        store(std::move(s)),
        connection(std::move(c)),
        insert_tracking(connection, insert_tracking_sql),
        insert_partner(connection, insert_partner_sql),
        insert_frame(connection, insert_frame_sql),
        insert_gaze(connection, insert_gaze_sql),
        insert_event(connection, insert_event_sql),
        insert_wait(connection, insert_wait_sql) {
    pending_tracking.reserve(cfg.max_batch);
    pending_frames.reserve(cfg.max_batch);
    pending_gaze.reserve(cfg.max_batch);
  }

  SampleWriterConfig config;
  SpscRing<TrackingSample> tracking;
  SpscRing<FrameRecord> frames;
  SpscRing<GazeSample> gaze;
  std::atomic<std::uint64_t> pushed_tracking{0}, pushed_frames{0}, pushed_gaze{0};
  std::atomic<std::uint64_t> dropped_tracking{0}, dropped_frames{0}, dropped_gaze{0};
  std::atomic<std::uint64_t> committed_tracking{0}, committed_frames{0}, committed_gaze{0};
  std::atomic<std::uint64_t> transactions{0}, failed_transactions{0};
  std::atomic<double> writer_cpu_s{0.0};
  std::atomic<bool> is_paused{false};
  std::atomic<std::int64_t> lock_wait_started_ns{0};  // steady clock; 0 while not waiting

  // Guards the fields below and the wake-ups; never held during disk I/O.
  mutable std::mutex mutex;
  std::condition_variable wake;      // writer waits on it
  std::condition_variable progress;  // flush() waits on it
  bool stop = false;
  std::uint64_t flush_requested = 0;
  std::uint64_t flush_done = 0;
  std::uint64_t failure_count = 0;
  std::string error;
  DataError::Kind error_kind = DataError::Kind::io;
  std::vector<JournalEntry> journal_queue;  // journalled, not yet taken by the writer
  std::uint64_t journal_pushed = 0;         // tickets handed out (1, 2, …)
  std::uint64_t journal_taken = 0;          // ticket of the last entry taken
  std::uint64_t journal_done = 0;           // ticket of the last entry applied

  // Owned by the writer thread only.
  SessionStore store;  // its own connection, synchronous = FULL
  std::deque<JournalEntry> journal_pending;
  Connection connection;
  Statement insert_tracking, insert_partner, insert_frame, insert_gaze, insert_event, insert_wait;
  // Since when the writer has found the file locked by another program (a
  // reader's checkpoint, another program's write transaction); the wait
  // to store as a logger_waited event once it has ended.
  std::optional<std::chrono::steady_clock::time_point> locked_since;
  std::chrono::steady_clock::time_point attempt_started;  // of the write being tried
  std::optional<std::pair<std::int64_t, std::string>> wait_to_log;  // ms, reason
  std::vector<TrackingSample> pending_tracking;
  std::vector<FrameRecord> pending_frames;
  std::vector<GazeSample> pending_gaze;
  std::uint64_t logged_drops_tracking = 0, logged_drops_frames = 0, logged_drops_gaze = 0;
  std::int64_t last_session_id = 0;
  // (session, eye geometry) of the last frame row that stored one: committed,
  // and within the batch being written.
  std::optional<std::pair<std::int64_t, ViewGeometry>> last_views, batch_views;
  std::thread thread;

  void bind_sample(const TrackingSample& s) {
    auto& st = insert_tracking;
    st.bind(1, s.session_id);
    if (s.trial_id >= 0) st.bind(2, s.trial_id); else st.bind_null(2);
    st.bind(3, s.frame_index).bind_static(4, to_string(s.device)).bind(5, s.t_ns);
    st.bind(6, s.lab_position_m[0]).bind(7, s.lab_position_m[1]).bind(8, s.lab_position_m[2]);
    st.bind(9, s.lab_orientation_xyzw[0]).bind(10, s.lab_orientation_xyzw[1]);
    st.bind(11, s.lab_orientation_xyzw[2]).bind(12, s.lab_orientation_xyzw[3]);
    st.bind(13, s.position_valid ? 1 : 0).bind(14, s.orientation_valid ? 1 : 0);
    if (s.has_virtual_pose) {
      // Little-endian IEEE doubles, column-major (x86-64 and ARM64 byte order).
      st.bind_blob(15, std::as_bytes(std::span<const double, 16>(s.virtual_pose)));
    } else {
      st.bind_null(15);
    }
    if (s.has_state) {
      st.bind(16, std::int64_t{s.state.physical_edge}).bind(17, std::int64_t{s.state.virtual_edge});
      st.bind(18, s.state.laps).bind(19, s.state.anchor_fraction);
      if (s.state.coherence_measured) st.bind(20, s.state.coherence_error_m).bind(21, s.state.coherence_error_rad);
      else st.bind_null(20).bind_null(21);
    } else {
      for (int i = 16; i <= 21; ++i) st.bind_null(i);
    }
  }

  void bind_partner(const TrackingSample& s) {
    auto& st = insert_partner;
    st.bind(1, s.session_id);
    if (s.trial_id >= 0) st.bind(2, s.trial_id); else st.bind_null(2);
    st.bind(3, s.frame_index).bind_static(4, s.device == TrackedDevice::other ? "cue" : to_string(s.device));
    st.bind(5, s.t_ns).bind_blob(6, std::as_bytes(std::span<const double, 16>(s.virtual_pose)));
    st.bind(7, std::int64_t{s.position_valid ? 1 : 0}).bind(8, std::int64_t{s.extrapolated ? 1 : 0});
    st.bind(9, s.sample_age_ns);
    if (s.distance_m >= 0.0) st.bind(10, s.distance_m); else st.bind_null(10);
  }

  void bind_frame(const FrameRecord& f) {
    auto& st = insert_frame;
    st.bind(1, f.session_id);
    if (f.trial_id >= 0) st.bind(2, f.trial_id); else st.bind_null(2);
    st.bind(3, f.frame_index).bind(4, f.t_ns);
    if (f.predicted_display_ns >= 0) st.bind(5, f.predicted_display_ns); else st.bind_null(5);
    st.bind(6, f.cpu_time_ns);
    if (f.gpu_time_ns >= 0) st.bind(7, f.gpu_time_ns); else st.bind_null(7);
    st.bind(8, std::int64_t{f.dropped_frames}).bind(9, std::int64_t{f.views});
    st.bind(10, std::int64_t{f.passes}).bind(11, std::int64_t{f.draws}).bind(12, f.triangles);
    if (f.display_period_ns > 0) st.bind(16, f.display_period_ns); else st.bind_null(16);
    st.bind(17, std::int64_t{f.late ? 1 : 0});
    // Eye geometry only where it differs from the last stored for the
    // session (the first frame of each run, then each change): an OpenXR
    // runtime may change the views every frame, most backends never do.
    const bool changed = f.has_view_geometry &&
                         (!batch_views || batch_views->first != f.session_id ||
                          !(batch_views->second == f.view_geometry));
    if (changed) {
      const auto& g = f.view_geometry;
      std::array<double, eye_views_doubles> packed{};
      encode_eye_views(g, packed);
      st.bind(13, std::int64_t{g.width_px}).bind(14, std::int64_t{g.height_px});
      st.bind_blob(15, std::as_bytes(std::span<const double, eye_views_doubles>(packed)));
      batch_views = std::pair{f.session_id, g};
    } else {
      for (int i = 13; i <= 15; ++i) st.bind_null(i);
    }
  }

  // One ray's columns from `first` on: valid, [confidence,] origin, direction;
  // all NULL where the headset does not track that ray.
  int bind_ray(int first, bool tracked, const GazeRayRecord& r, bool with_confidence) {
    auto& st = insert_gaze;
    const int n = with_confidence ? 8 : 7;
    if (!tracked) {
      for (int i = first; i < first + n; ++i) st.bind_null(i);
      return first + n;
    }
    int k = first;
    st.bind(k++, std::int64_t{r.valid ? 1 : 0});
    if (with_confidence) {
      if (r.confidence >= 0.0) st.bind(k++, r.confidence); else st.bind_null(k++);
    }
    for (double v : r.origin_m) st.bind(k++, v);
    for (double v : r.direction) st.bind(k++, v);
    return k;
  }

  void bind_gaze(const GazeSample& g) {
    auto& st = insert_gaze;
    st.bind(1, g.session_id);
    if (g.trial_id >= 0) st.bind(2, g.trial_id); else st.bind_null(2);
    st.bind(3, g.frame_index).bind(4, g.t_ns);
    int k = bind_ray(5, g.has_combined, g.combined, false);
    k = bind_ray(k, g.has_eyes, g.eyes[0], true);
    k = bind_ray(k, g.has_eyes, g.eyes[1], true);
    if (g.has_vergence) st.bind(k, g.vergence_rad); else st.bind_null(k);
    if (g.has_vergence && g.vergence_distance_m > 0.0) st.bind(k + 1, g.vergence_distance_m);
    else st.bind_null(k + 1);
  }

  // Writes the pending batch in one transaction; on failure keeps it.
  bool write_pending() {
    const std::uint64_t dt = dropped_tracking.load(std::memory_order_relaxed);
    const std::uint64_t df = dropped_frames.load(std::memory_order_relaxed);
    const std::uint64_t dg = dropped_gaze.load(std::memory_order_relaxed);
    const bool log_drops =
        (dt != logged_drops_tracking || df != logged_drops_frames || dg != logged_drops_gaze) && last_session_id > 0;
    const bool log_wait = wait_to_log && last_session_id > 0;
    if (pending_tracking.empty() && pending_frames.empty() && pending_gaze.empty() && !log_drops && !log_wait)
      return true;
    // The geometry last stored advances only with a committed batch: a
    // batch that fails is written again from the same starting point.
    batch_views = last_views;
    attempt_started = std::chrono::steady_clock::now();
    try {
      Transaction txn(connection);
      for (const auto& s : pending_tracking) {
        if (s.partner) {
          bind_partner(s);
          insert_partner.run();
        } else {
          bind_sample(s);
          insert_tracking.run();
        }
      }
      for (const auto& f : pending_frames) {
        bind_frame(f);
        insert_frame.run();
      }
      for (const auto& g : pending_gaze) {
        bind_gaze(g);
        insert_gaze.run();
      }
      if (log_drops) {
        insert_event.bind(1, last_session_id).bind(2, std::int64_t{0});
        insert_event.bind(3, static_cast<std::int64_t>(dt)).bind(4, static_cast<std::int64_t>(df));
        insert_event.bind(5, static_cast<std::int64_t>(dg));
        insert_event.run();
      }
      if (log_wait) {
        insert_wait.bind(1, last_session_id).bind(2, wait_to_log->first).bind(3, wait_to_log->second);
        insert_wait.run();
      }
      txn.commit();
    } catch (const SqliteFailure& failure) {
      note_failure(to_data_error(failure, connection.path()), "tracking/frame logging paused");
      return false;
    }
    note_success();
    if (log_wait) wait_to_log.reset();
    last_views = batch_views;
    if (log_drops) {
      logged_drops_tracking = dt;
      logged_drops_frames = df;
      logged_drops_gaze = dg;
    }
    transactions.fetch_add(1, std::memory_order_relaxed);
    committed_tracking.fetch_add(pending_tracking.size(), std::memory_order_relaxed);
    committed_frames.fetch_add(pending_frames.size(), std::memory_order_relaxed);
    committed_gaze.fetch_add(pending_gaze.size(), std::memory_order_relaxed);
    pending_tracking.clear();
    pending_frames.clear();
    pending_gaze.clear();
    is_paused.store(false, std::memory_order_release);
    return true;
  }

  // A lock held by another program (busy) is waited out for up to
  // config.lock_patience: the writer keeps what it holds and retries, the
  // rings absorb the meantime, and nobody waiting on it is told of a
  // failure. Anything else, or a longer wait, is a failure.
  void note_failure(const DataError& e, const char* what) {
    failed_transactions.fetch_add(1, std::memory_order_relaxed);
    is_paused.store(true, std::memory_order_release);
    if (e.kind == DataError::Kind::busy) {
      const auto now = std::chrono::steady_clock::now();
      if (!locked_since) {
        locked_since = attempt_started;
        lock_wait_started_ns.store(attempt_started.time_since_epoch().count(), std::memory_order_relaxed);
      }
      if (now - *locked_since < config.lock_patience) return;
    }
    {
      std::lock_guard lock(mutex);
      error = std::string(what) + ": " + e.message;
      error_kind = e.kind;
      ++failure_count;
    }
    progress.notify_all();
  }

  // Ends a wait for another program's lock, keeping how long it lasted.
  void note_success() {
    if (!locked_since) return;
    const auto waited = std::chrono::steady_clock::now() - *locked_since;
    wait_to_log = std::pair{std::chrono::duration_cast<std::chrono::milliseconds>(waited).count(),
                            std::string("another program held the file's lock")};
    locked_since.reset();
    lock_wait_started_ns.store(0, std::memory_order_relaxed);
  }

  // One journal entry, or a run of consecutive events in one transaction;
  // returns how many entries were applied.
  Expected<std::size_t> apply_front() {
    if (std::holds_alternative<EventRecord>(journal_pending.front())) {
      std::vector<EventRecord> events;
      for (const auto& e : journal_pending) {
        if (!std::holds_alternative<EventRecord>(e) || events.size() == 256) break;
        events.push_back(std::get<EventRecord>(e));
      }
      if (auto r = store.record_events(events); !r) return r.error();
      return events.size();
    }
    auto done = std::visit(
        [&](const auto& entry) -> Expected<Done> {
          using T = std::decay_t<decltype(entry)>;
          if constexpr (std::is_same_v<T, BeginTrial>) {
            auto r = store.begin_trial(entry.trial_id);
            if (!r) return r.error();
            return Done{};
          } else if constexpr (std::is_same_v<T, TrialResult>) {
            return store.complete_trial(entry);
          } else if constexpr (std::is_same_v<T, EndUnanswered>) {
            return entry.aborted ? store.abort_trial(entry.trial_id, entry.reason)
                                 : store.skip_trial(entry.trial_id, entry.reason);
          } else if constexpr (std::is_same_v<T, ShotRecord>) {
            return store.record_shot(entry);
          } else if constexpr (std::is_same_v<T, QuestionnaireAnswer>) {
            return store.record_answer(entry);
          } else if constexpr (std::is_same_v<T, QuestionnaireScores>) {
            return store.record_scores(entry.rows);
          } else if constexpr (std::is_same_v<T, StatusChange>) {
            return entry.close ? store.close_session(entry.session_id, entry.status)
                               : store.set_session_status(entry.session_id, entry.status);
          } else {
            return Done{};
          }
        },
        journal_pending.front());
    if (!done) return done.error();
    return std::size_t{1};
  }

  // Applies the taken entries in order; stops at the first failure, which
  // stays at the front to be retried.
  bool apply_journal() {
    while (!journal_pending.empty()) {
      attempt_started = std::chrono::steady_clock::now();
      auto applied = apply_front();
      if (!applied) {
        note_failure(applied.error(), "event and trial logging paused");
        return false;
      }
      note_success();
      for (std::size_t i = 0; i < applied.value(); ++i) journal_pending.pop_front();
      {
        std::lock_guard lock(mutex);
        journal_done = journal_taken - journal_pending.size();
      }
      progress.notify_all();
    }
    is_paused.store(false, std::memory_order_release);
    return true;
  }

  void run() {
    for (;;) {
      std::uint64_t ticket = 0;
      bool stopping = false;
      {
        std::unique_lock lock(mutex);
        const auto interval = is_paused.load() ? config.retry_interval : config.batch_interval;
        wake.wait_for(lock, interval, [&] { return stop || flush_requested != flush_done; });
        ticket = flush_requested;
        stopping = stop;
        // Taken before the rings are drained: samples pushed before an
        // entry are committed before it.
        for (auto& e : journal_queue) journal_pending.push_back(std::move(e));
        journal_queue.clear();
        journal_taken = journal_pushed;
      }
      // Drain and write until the rings are empty (or a write fails), so a
      // flush ticket read above covers everything pushed before it.
      bool ok = true;
      for (;;) {
        if (pending_tracking.empty() && pending_frames.empty() && pending_gaze.empty()) {
          tracking.pop_into(pending_tracking, config.max_batch);
          frames.pop_into(pending_frames, config.max_batch);
          gaze.pop_into(pending_gaze, config.max_batch);
          if (!pending_tracking.empty()) last_session_id = pending_tracking.back().session_id;
          else if (!pending_frames.empty()) last_session_id = pending_frames.back().session_id;
          else if (!pending_gaze.empty()) last_session_id = pending_gaze.back().session_id;
        }
        const bool had_work = !pending_tracking.empty() || !pending_frames.empty() || !pending_gaze.empty();
        ok = write_pending();
        if (!ok || !had_work) break;
      }
      if (ok) ok = apply_journal();
      writer_cpu_s.store(thread_cpu_seconds(), std::memory_order_relaxed);
      if (ok) {
        std::lock_guard lock(mutex);
        flush_done = std::max(flush_done, ticket);
      }
      progress.notify_all();
      if (stopping && (ok || shutdown_deadline_passed())) return;
    }
  }

  std::chrono::milliseconds wait_limit(std::chrono::milliseconds timeout) const;

  std::chrono::steady_clock::time_point stop_time{};
  bool shutdown_deadline_passed() const {
    return std::chrono::steady_clock::now() - stop_time > config.shutdown_timeout;
  }
};

Expected<std::unique_ptr<SampleWriter>> SampleWriter::open(const std::string& path,
                                                           SampleWriterConfig config) {
  // The journal's connection: synchronous = FULL, so an applied entry is on disk.
  auto db = Database::open(path, OpenMode::open_existing);
  if (!db) return db.error();
  try {
    Connection c = Connection::open(path, OpenFlags::read_write);
    // NORMAL: a batch commit does not wait for fsync; WAL keeps the file
    // consistent after a crash, and the next journal commit (FULL) syncs
    // the WAL including these batches.
    configure_connection(c, false);
    auto impl = std::make_unique<Impl>(std::move(c), SessionStore(std::move(db).value()), config);
    std::unique_ptr<SampleWriter> writer(new SampleWriter(std::move(impl)));
    return writer;
  } catch (const SqliteFailure& failure) {
    return to_data_error(failure, path);
  }
}

SampleWriter::SampleWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {
  impl_->thread = std::thread([impl = impl_.get()] { impl->run(); });
}

SampleWriter::~SampleWriter() {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stop = true;
    impl_->stop_time = std::chrono::steady_clock::now();
  }
  impl_->wake.notify_all();
  if (impl_->thread.joinable()) impl_->thread.join();
}

bool SampleWriter::push_tracking(const TrackingSample& sample) noexcept {
  if (impl_->tracking.try_push(sample)) {
    impl_->pushed_tracking.fetch_add(1, std::memory_order_relaxed);
    return true;
  }
  impl_->dropped_tracking.fetch_add(1, std::memory_order_relaxed);
  return false;
}

bool SampleWriter::push_frame(const FrameRecord& frame) noexcept {
  if (impl_->frames.try_push(frame)) {
    impl_->pushed_frames.fetch_add(1, std::memory_order_relaxed);
    return true;
  }
  impl_->dropped_frames.fetch_add(1, std::memory_order_relaxed);
  return false;
}

bool SampleWriter::push_gaze(const GazeSample& sample) noexcept {
  if (impl_->gaze.try_push(sample)) {
    impl_->pushed_gaze.fetch_add(1, std::memory_order_relaxed);
    return true;
  }
  impl_->dropped_gaze.fetch_add(1, std::memory_order_relaxed);
  return false;
}

std::chrono::milliseconds SampleWriter::Impl::wait_limit(std::chrono::milliseconds timeout) const {
  // By default a waiter outlasts the writer's own patience with another
  // program's lock, plus one SQLite busy timeout.
  if (timeout.count() > 0) return timeout;
  return config.lock_patience + std::chrono::seconds(10);
}

Expected<Done> SampleWriter::flush(std::chrono::milliseconds timeout) {
  timeout = impl_->wait_limit(timeout);
  std::unique_lock lock(impl_->mutex);
  const std::uint64_t ticket = ++impl_->flush_requested;
  const std::uint64_t failures_before = impl_->failure_count;
  impl_->wake.notify_all();
  const bool finished = impl_->progress.wait_for(lock, timeout, [&] {
    return impl_->flush_done >= ticket || impl_->failure_count != failures_before;
  });
  if (impl_->flush_done >= ticket) return Done{};
  if (!finished)
    return DataError{DataError::Kind::busy, "tracking/frame flush timed out after " +
                                                std::to_string(timeout.count()) + " ms"};
  return DataError{impl_->error_kind, impl_->error};
}

std::uint64_t SampleWriter::journal(JournalEntry entry) {
  std::lock_guard lock(impl_->mutex);
  impl_->journal_queue.push_back(std::move(entry));
  return ++impl_->journal_pushed;
}

bool SampleWriter::durable(std::uint64_t ticket) const {
  std::lock_guard lock(impl_->mutex);
  return impl_->journal_done >= ticket;
}

Expected<Done> SampleWriter::wait_durable(std::uint64_t ticket, std::chrono::milliseconds timeout) {
  timeout = impl_->wait_limit(timeout);
  std::unique_lock lock(impl_->mutex);
  if (impl_->journal_done >= ticket) return Done{};
  ++impl_->flush_requested;  // wakes the writer now rather than at its next interval
  const std::uint64_t failures_before = impl_->failure_count;
  impl_->wake.notify_all();
  const bool finished = impl_->progress.wait_for(lock, timeout, [&] {
    return impl_->journal_done >= ticket || impl_->failure_count != failures_before;
  });
  if (impl_->journal_done >= ticket) return Done{};
  if (!finished)
    return DataError{DataError::Kind::busy, "writing the session's trial record timed out after " +
                                                std::to_string(timeout.count()) + " ms"};
  return DataError{impl_->error_kind, impl_->error};
}

SampleWriterStats SampleWriter::stats() const {
  SampleWriterStats s;
  s.pushed_tracking = impl_->pushed_tracking.load();
  s.pushed_frames = impl_->pushed_frames.load();
  s.dropped_tracking = impl_->dropped_tracking.load();
  s.dropped_frames = impl_->dropped_frames.load();
  s.committed_tracking = impl_->committed_tracking.load();
  s.committed_frames = impl_->committed_frames.load();
  s.pushed_gaze = impl_->pushed_gaze.load();
  s.dropped_gaze = impl_->dropped_gaze.load();
  s.committed_gaze = impl_->committed_gaze.load();
  s.transactions = impl_->transactions.load();
  s.failed_transactions = impl_->failed_transactions.load();
  s.writer_cpu_s = impl_->writer_cpu_s.load();
  {
    std::lock_guard lock(impl_->mutex);
    s.journalled = impl_->journal_pushed;
    s.journal_applied = impl_->journal_done;
  }
  return s;
}

bool SampleWriter::paused() const { return impl_->is_paused.load(); }

double SampleWriter::lock_wait_s() const {
  const std::int64_t since = impl_->lock_wait_started_ns.load(std::memory_order_relaxed);
  if (since == 0) return 0.0;
  const std::int64_t now = std::chrono::steady_clock::now().time_since_epoch().count();
  return std::chrono::duration<double>(std::chrono::steady_clock::duration(now - since)).count();
}

std::string SampleWriter::last_error() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->error;
}

}  // namespace curvlab::harness::data
