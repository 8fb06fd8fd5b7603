// A pose source that hands the session a pose no lab can hold — NaN, or a
// position of 1e308 m, as a faulty runtime might — in a whole session in
// process: the samples are stored as lost tracking (validity 0, no virtual
// pose, no coherence error), never as coherent, the session goes on, and a
// replay of such a frame says why it cannot draw it.
#include "in_process.hpp"

#include "curvlab/harness/runner/replay.hpp"

#include <limits>

namespace {

using namespace curvlab;
using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::run_protocol;
using curvlab::testing::ScriptedDevices;
using geometry::Device;
namespace rn = harness::runner;

using Rows = std::vector<std::vector<std::string>>;

constexpr std::int64_t kMs = 1'000'000;

}  // namespace

TEST(InvalidPoses, APoseNoLabCanHoldIsStoredAsLostNeverAsCoherent) {
  const auto out = run_protocol("demo", "invalid_poses", "[tracking]\non_loss = \"flag\"\n", true,
                                [](ScriptedDevices& b) {
                                  b.alter_poses = [](std::int64_t t_ns, geometry::LabFrame& f) {
                                    if (t_ns >= 150 * kMs && t_ns < 250 * kMs)
                                      f[Device::head].position_m.x = std::numeric_limits<double>::quiet_NaN();
                                    if (t_ns >= 300 * kMs && t_ns < 400 * kMs)
                                      f[Device::right_hand].position_m.y = 1e308;
                                  };
                                });
  ASSERT_FALSE(out.db.empty());
  EXPECT_EQ(out.summary.trials_completed, 8);
  // Each spell's frames: the device lost, nothing placed, no coherence.
  const auto lost = query(out.db, "SELECT device, COUNT(*), SUM(virtual_pose IS NULL), MAX(abs(lab_px_m)), "
                                  "MAX(abs(lab_py_m)) FROM tracking_samples WHERE position_valid = 0 "
                                  "GROUP BY device ORDER BY device");
  ASSERT_EQ(lost.size(), 2u) << ::testing::PrintToString(lost);
  EXPECT_EQ(lost[0][0], "head");
  EXPECT_EQ(lost[1][0], "right_hand");
  for (const auto& row : lost) {
    EXPECT_GE(std::stoi(row[1]), 8) << row[0];  // about 9 frames at 90 Hz
    EXPECT_EQ(row[2], row[1]) << row[0];
    EXPECT_EQ(row[3], "0.0") << row[0];
    EXPECT_EQ(row[4], "0.0") << row[0];
  }
  // No hand is stored as coherent where it or the head was not placed.
  EXPECT_EQ(query(out.db, "SELECT COUNT(*) FROM tracking_samples h JOIN tracking_samples x ON "
                          "x.frame_index = h.frame_index AND x.device != 'head' WHERE h.device = 'head' AND "
                          "(h.position_valid = 0 OR x.position_valid = 0) AND x.coherence_error_m IS NOT NULL")[0][0],
            "0");
  // Every hand placed while the head was has its coherence error.
  EXPECT_EQ(query(out.db, "SELECT COUNT(*) FROM tracking_samples h JOIN tracking_samples x ON "
                          "x.frame_index = h.frame_index AND x.device != 'head' WHERE h.device = 'head' AND "
                          "h.position_valid = 1 AND x.position_valid = 1 AND x.coherence_error_m IS NULL")[0][0],
            "0");

  // Replaying a frame of the head's spell names the reason instead of
  // drawing a black image.
  const auto frame = query(out.db, "SELECT MIN(frame_index), trial_id FROM tracking_samples "
                                   "WHERE device = 'head' AND position_valid = 0");
  ASSERT_EQ(query(out.db, "SELECT trial_index FROM trials WHERE trial_id = " + frame[0][1])[0][0], "0");
  rn::ReplayRequest rq;
  rq.db_path = out.db;
  rq.session_id = out.summary.session_id;
  rq.trial_index = 0;
  rq.frame_index = std::stoll(frame[0][0]);
  rq.out_dir = (fresh_dir("invalid_poses_replay") / "out").string();
  rq.software = true;
  const auto replayed = rn::replay_frame(rq);
  ASSERT_FALSE(replayed.has_value());
  EXPECT_EQ(replayed.error().kind, harness::Error::Kind::bad_input);
  EXPECT_NE(replayed.error().message.find("frame " + frame[0][0] + " of trial 0 has no valid head pose"),
            std::string::npos)
      << replayed.error().message;
}
