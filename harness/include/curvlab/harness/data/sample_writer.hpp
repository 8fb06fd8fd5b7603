// The asynchronous half of the logger: tracking samples, frame records and gaze samples go
// from the frame loop into bounded lock-free rings, and a writer thread with
// its own connection commits them in batched transactions (DESIGN.md §7).
//
// Back-pressure policy: the frame loop never blocks and never touches the
// disk. push_*() copies the record into a fixed-capacity single-producer /
// single-consumer ring and returns at once; when a ring is full the new
// record is dropped and counted (stats().dropped_*), and the writer stores
// each change of the drop counts as a "logger_drops" event. Memory is
// bounded by the capacities in SampleWriterConfig plus one batch per ring
// held by the writer. If a batch cannot be written (disk full, read-only,
// lock held too long) the writer keeps that batch, stops draining, reports
// paused() with the reason, and retries every retry interval; the rings
// absorb the meantime and then drop. A kill at any instant loses at most the
// records not yet committed: the rings plus one batch.
//
// The session's events and trial-state changes go the same way, in order,
// through journal(): the entry is queued under a mutex that is never held
// during disk I/O, and the writer applies it after the samples pushed before
// it, through a second connection with synchronous = FULL, so an applied
// entry is on disk. A failed entry is kept (with the ones after it) and
// retried like a failed batch; wait_durable() reports the failure.
//
// Readers cannot end a session: when another program holds the file's lock
// (a reader's PRAGMA wal_checkpoint(TRUNCATE) waiting on a long SELECT, a
// write transaction left open in DB Browser), SQLite answers busy. The
// writer then waits it out — keeps its batch and journal, retries every
// retry interval, shows lock_wait_s() to the operator — for up to
// lock_patience before it reports a failure, and stores the wait as a
// "logger_waited" event once it is over. Waiters (flush(), wait_durable())
// by default wait longer than that patience.
//
// Thread-safety: push_tracking(), push_frame(), push_gaze() and journal() must be called
// from one producer thread (the frame loop). flush(), wait_durable(),
// durable(), stats(), paused() and last_error() may be called from any thread. The writer thread is owned by
// this object; the destructor writes what is left (bounded by
// shutdown_timeout) and joins it. Move is not offered: the thread refers to
// the object.
#pragma once

#include "curvlab/harness/data/error.hpp"
#include "curvlab/harness/data/journal.hpp"
#include "curvlab/harness/data/records.hpp"

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

namespace curvlab::harness::data {

struct SampleWriterConfig {
  // 32768 samples ≈ 10.9 s of 3 devices at 1 kHz (about 9.4 MiB).
  std::size_t tracking_capacity = 1u << 15;
  // 4096 frames ≈ 45 s at 90 Hz.
  std::size_t frame_capacity = 1u << 12;
  // 4096 gaze samples ≈ 45 s at 90 Hz (one per frame; about 1.2 MiB).
  std::size_t gaze_capacity = 1u << 12;
  // Most records one transaction takes from each ring.
  std::size_t max_batch = 8192;
  // How often the writer wakes to drain the rings when not asked to flush.
  std::chrono::milliseconds batch_interval{20};
  // How long the writer waits before retrying a failed batch.
  std::chrono::milliseconds retry_interval{500};
  std::chrono::milliseconds shutdown_timeout{5000};
  // How long another program may hold the file's lock before the writer
  // gives up (the session then ends interrupted, resumable).
  std::chrono::milliseconds lock_patience{120'000};
};

struct SampleWriterStats {
  std::uint64_t pushed_tracking = 0;
  std::uint64_t pushed_frames = 0;
  std::uint64_t dropped_tracking = 0;
  std::uint64_t dropped_frames = 0;
  std::uint64_t committed_tracking = 0;
  std::uint64_t committed_frames = 0;
  std::uint64_t pushed_gaze = 0;
  std::uint64_t dropped_gaze = 0;
  std::uint64_t committed_gaze = 0;
  std::uint64_t transactions = 0;
  std::uint64_t failed_transactions = 0;
  std::uint64_t journalled = 0;  // events and trial-state changes queued
  std::uint64_t journal_applied = 0;
  double writer_cpu_s = 0.0;  // CPU time of the writer thread
};

class SampleWriter {
 public:
  // Opens its own connection to an existing, current curvlab file.
  static Expected<std::unique_ptr<SampleWriter>> open(const std::string& path,
                                                      SampleWriterConfig config = {});
  ~SampleWriter();
  SampleWriter(const SampleWriter&) = delete;
  SampleWriter& operator=(const SampleWriter&) = delete;

  // Producer side: never blocks; false when the record was dropped.
  bool push_tracking(const TrackingSample& sample) noexcept;
  bool push_frame(const FrameRecord& frame) noexcept;
  bool push_gaze(const GazeSample& sample) noexcept;

  // Queues an event or trial-state change; never blocks on the disk. The
  // returned ticket is durable once the writer has applied the entry.
  std::uint64_t journal(JournalEntry entry);
  [[nodiscard]] bool durable(std::uint64_t ticket) const;
  // Blocks until the entry with `ticket` (and every one before it) is on
  // disk, or returns the writer's error, or a busy error after `timeout`.
  // Call it between trials, never inside a frame.
  // A zero timeout: lock_patience plus 10 s.
  Expected<Done> wait_durable(std::uint64_t ticket, std::chrono::milliseconds timeout = {});

  // Blocks until every record pushed before the call is committed (call it at
  // a trial's end, not inside the frame loop), or returns the writer's error
  // when it is paused, or a busy error after `timeout`.
  Expected<Done> flush(std::chrono::milliseconds timeout = {});

  SampleWriterStats stats() const;
  bool paused() const;
  // Seconds the writer has been waiting for another program's lock on the
  // file; 0 when it is not waiting.
  double lock_wait_s() const;
  std::string last_error() const;

  struct Impl;

 private:
  explicit SampleWriter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace curvlab::harness::data
