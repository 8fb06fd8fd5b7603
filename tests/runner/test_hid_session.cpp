// A session answered by a HID button box: a recorded report stream is
// replayed through the real reader thread and mapping into a real-time
// headless session (docs/devices.md). Every trial is answered from the
// device, and each response time stamp is the moment its report was read, on
// the session clock.
#include "session_db.hpp"

#include "curvlab/harness/devices/responses.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/headless.hpp"
#include "curvlab/harness/runner/session.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace curvlab;
namespace rn = harness::runner;
namespace pr = harness::protocol;
namespace dv = curvlab::harness::devices;
using curvlab::testing::fresh_dir;
using curvlab::testing::query;

// The demo's four conditions once, answered only by buttons (no keys).
std::string button_protocol() {
  std::ifstream in(std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  s = s.substr(0, s.find("[session]"));
  s += "[session]\nrepetitions = 1\n\n[judgement]\ntype = \"choice\"\nprompt = \"Convex or concave?\"\n"
       "options = [\n  { value = \"convex\", buttons = [\"hid_1\"] },\n"
       "  { value = \"concave\", buttons = [\"hid_2\"] },\n]\n";
  return s;
}

TEST(HidSession, ARecordedButtonBoxAnswersEveryTrialOnTheSessionClock) {
  const std::string text = button_protocol();
  auto loaded = pr::load_protocol_text(text, "buttons.toml");
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  const auto& p = *loaded;

  rn::HeadlessOptions ho;
  ho.pace = rn::Pace::realtime;
  ho.no_gpu = true;
  ho.refresh_hz = p.refresh_hz;
  auto made = rn::HeadlessDevices::create(ho, rn::standing_at(rn::nominal_calibration(p.session_settings())));
  ASSERT_TRUE(made.has_value()) << made.error().message;
  auto& headless = made.value();
  const harness::io::Clock& clock = headless.clock();

  // Byte 0, bit 0 is hid_1 (convex): pressed for 40 ms every 450 ms from 0.3 s on, for
  // 20 s — through every response window of the four trials.
  dv::DeviceMapping box;
  box.name = "box";
  box.bindings = {{"hid_1", dv::BitBinding{0, 0}}, {"hid_2", dv::BitBinding{0, 1}}};
  std::vector<dv::RecordedReports::Report> reports;
  std::vector<std::int64_t> presses;
  const std::int64_t t0 = headless.display->first_ns();
  for (std::int64_t t = t0 + 300'000'000; t < t0 + 20'000'000'000; t += 450'000'000) {
    presses.push_back(t);
    reports.push_back({t, {0x01}});
    reports.push_back({t + 40'000'000, {0x00}});
  }
  std::vector<std::pair<std::unique_ptr<dv::ReportSource>, dv::DeviceMapping>> sources;
  sources.emplace_back(std::make_unique<dv::RecordedReports>(std::move(reports), clock, "recorded box"), box);
  auto hid = dv::HidResponses::read(std::move(sources), clock);

  harness::io::Station station = headless.station();
  station.responses.push_back(hid.get());
  rn::RunOptions o;
  o.participant = "H01";
  o.drawing = rn::FrameDrawing::none;
  const auto db = (fresh_dir("hid_session") / "s.sqlite").string();
  auto result = rn::run_session(p, text, db, o, station, clock);
  ASSERT_TRUE(result.has_value()) << result.error().message;
  EXPECT_EQ(result->status, curvlab::harness::data::SessionStatus::completed);
  EXPECT_EQ(result->trials_completed, 4);

  const auto rows = query(db, "SELECT response, response_device, onset_ns, response_ns, rt_ns FROM trials "
                              "WHERE status = 'completed' ORDER BY trial_index");
  ASSERT_EQ(rows.size(), 4u);
  for (const auto& r : rows) {
    EXPECT_EQ(r[0], "convex");
    EXPECT_EQ(r[1], "hid:box");
    const std::int64_t onset = std::stoll(r[2]);
    const std::int64_t at = std::stoll(r[3]);
    EXPECT_EQ(std::stoll(r[4]), at - onset);
    // The answer is the first press after the onset, stamped when the reader
    // read it: at the press, plus the read's latency (well under one press
    // interval, even on a loaded machine).
    const auto first = std::find_if(presses.begin(), presses.end(), [&](std::int64_t t) { return t >= onset; });
    ASSERT_NE(first, presses.end());
    EXPECT_GE(at, *first);
    EXPECT_LT(at - *first, 400'000'000) << "the response was not the first press after the onset";
  }
}

}  // namespace
