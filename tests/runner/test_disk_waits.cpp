// The frame loop never waits on the disk: from its first frame to its last,
// every disk sync of a session comes from the logger's writer thread, never
// from the thread that runs the frames, counted through an SQLite VFS shim
// that sees every xSync with the thread that issued it. (Creating the
// session before the first frame and closing the file after the last are
// the frame thread's own, synchronous work.) Durability is kept: each completed trial is on disk
// before the next trial starts.
#include "in_process.hpp"
#include "sync_vfs.hpp"

#include <gtest/gtest.h>

#include <thread>

using namespace curvlab::testing;
namespace vfs = curvlab::testing::sync_vfs;

TEST(DiskWaits, NoSyncFromTheFrameThreadAndEachTrialIsDurableBeforeTheNext) {
  vfs::install();
  vfs::set_sync_delay(std::chrono::milliseconds(2));  // a slowish disk
  vfs::reset();
  std::thread::id frame_thread;
  std::int64_t syncs_before_loop = -1;
  std::int64_t loop_syncs = 0;  // from the first frame to the last
  std::string db_path;
  std::string last_phase;
  int trials_started = 0;
  std::vector<std::pair<int, int>> durable_at_start;  // (trials started before, trials completed on disk)
  const auto out = run_protocol("demo", "disk_waits", "", true, [&](ScriptedDevices& b) {
    b.inputs = [&](const curvlab::harness::io::FrameTiming&, const std::string& phase, std::vector<curvlab::harness::io::InputEvent>&) {
      if (syncs_before_loop < 0) {
        frame_thread = std::this_thread::get_id();
        syncs_before_loop = vfs::syncs_from(frame_thread);
        db_path = (test_dir("in_process_disk_waits") / "s.sqlite").string();  // where run_protocol writes
      }
      loop_syncs = vfs::syncs_from(frame_thread) - syncs_before_loop;
      if (phase == "fixation" && last_phase != "fixation") {
        // A read on its own connection sees only committed rows; it runs on
        // a thread of its own so that its file access is not the frame thread's.
        std::vector<std::vector<std::string>> done;
        std::thread([&] { done = query(db_path, "SELECT COUNT(*) FROM trials WHERE status = 'completed'"); }).join();
        durable_at_start.emplace_back(trials_started, done.empty() ? -1 : std::stoi(done[0][0]));
        ++trials_started;
      }
      last_phase = phase;
      return rn::Signal::none;
    };
  });
  vfs::set_sync_delay(std::chrono::microseconds(0));
  ASSERT_EQ(out.summary.status, curvlab::harness::data::SessionStatus::completed);
  EXPECT_EQ(loop_syncs, 0) << "disk syncs issued by the frame loop";
  EXPECT_GT(vfs::total_syncs() - vfs::syncs_from(frame_thread), out.summary.trials_completed)
      << "the writer thread syncs at least once per completed trial";
  ASSERT_EQ(static_cast<std::int64_t>(durable_at_start.size()), out.summary.trials_completed);
  for (const auto& [started, completed] : durable_at_start) EXPECT_EQ(completed, started) << "trial " << started;
  // Nothing journalled was lost: every onset and trial row is there.
  EXPECT_EQ(query(out.db, "SELECT COUNT(*) FROM events WHERE kind = 'onset'")[0][0],
            std::to_string(out.summary.trials_completed));
  EXPECT_EQ(query(out.db, "SELECT status FROM sessions")[0][0], "completed");
}
