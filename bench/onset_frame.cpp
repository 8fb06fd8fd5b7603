// What the disk costs the frame loop. Whole headless sessions of a protocol
// run with the simulated observer while an SQLite VFS shim makes every disk
// sync wait a set time (0 ms: a local SSD; 8 ms: a spinning disk; 30 ms: a
// network share). For each frame the benchmark measures the runner's loop
// time — from the display handing out the frame to the runner asking for the
// next one, so anything that holds the next frame back counts — and reports
// it for stimulus-onset frames and for all frames, with the disk syncs
// issued from the frame thread and from other threads.
//
//   bench_onset_frame [protocol] [delays_ms,...] [fast|realtime]   (default: demo 0,8,30 fast)
//
// Fast pace runs the inter-trial interval in no time, so a trial's durable
// commit, which the real-time runner overlaps with the interval, shows as
// a long interval frame there; realtime shows what a participant gets.
#include "sync_vfs.hpp"

#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/headless.hpp"
#include "curvlab/harness/runner/session.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace rn = curvlab::harness::runner;
namespace pr = curvlab::harness::protocol;
namespace vfs = curvlab::testing::sync_vfs;
using Clock = std::chrono::steady_clock;

namespace {

// Forwards to the headless display and times the runner's work per frame.
class TimingDisplay final : public curvlab::harness::io::Display {
 public:
  explicit TimingDisplay(rn::HeadlessDisplay& inner) : inner_(inner) {}

  [[nodiscard]] curvlab::harness::io::DisplayInfo info() const override { return inner_.info(); }
  std::optional<curvlab::harness::io::FrameTiming> begin_frame() override {
    close_frame();
    // Disk syncs this thread issued from the first frame on.
    const auto syncs = vfs::syncs_from(std::this_thread::get_id());
    if (first_syncs < 0) first_syncs = syncs;
    loop_syncs = syncs - first_syncs;
    auto t = inner_.begin_frame();
    handed_out_ = Clock::now();
    open_ = t.has_value();
    return t;
  }
  curvlab::renderer::StereoRig rig(const curvlab::harness::io::FrameTiming& frame, double ipd_m) override {
    return inner_.rig(frame, ipd_m);
  }
  curvlab::renderer::FrameStats submit(const curvlab::renderer::Scene& scene,
                                       const curvlab::renderer::FrameDescription& frame,
                                       const curvlab::harness::io::Overlay& overlay, bool draw) override {
    const bool stimulus = is_stimulus(overlay);
    onset_ = stimulus && !last_stimulus_;
    last_stimulus_ = stimulus;
    return inner_.submit(scene, frame, overlay, draw);
  }

  std::vector<double> onset_ms, all_ms;
  std::int64_t first_syncs = -1, loop_syncs = 0;

 private:
  static bool is_stimulus(const curvlab::harness::io::Overlay& overlay) { return overlay.phase == curvlab::harness::io::Phase::stimulus; }
  void close_frame() {
    if (!open_) return;
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - handed_out_).count();
    all_ms.push_back(ms);
    if (onset_) onset_ms.push_back(ms);
    onset_ = false;
    open_ = false;
  }
  rn::HeadlessDisplay& inner_;
  Clock::time_point handed_out_;
  bool open_ = false, onset_ = false, last_stimulus_ = false;
};

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

}  // namespace

int main(int argc, char** argv) {
  const std::string name = argc > 1 ? argv[1] : "demo";
  std::vector<int> delays{0, 8, 30};
  if (argc > 2) {
    delays.clear();
    std::stringstream list(argv[2]);
    for (std::string item; std::getline(list, item, ',');) delays.push_back(std::stoi(item));
  }
  const bool realtime = argc > 3 && std::string(argv[3]) == "realtime";
  vfs::install();
  const std::string path = CURVLAB_SOURCE_DIR "/protocols/" + name + ".toml";
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  auto loaded = pr::load_protocol_text(text.str(), path);
  if (!loaded) {
    std::fprintf(stderr, "%s does not load\n", path.c_str());
    return 1;
  }
  const auto& p = *loaded;
  const auto tmp = std::filesystem::temp_directory_path() / "curvlab_bench_onset";
  std::filesystem::remove_all(tmp);
  std::filesystem::create_directories(tmp);

  std::printf("protocol %s, headless %s pace, nothing drawn, simulated observer\n", name.c_str(),
              realtime ? "realtime" : "fast");
  std::printf("%8s %7s %7s | %9s %9s %9s | %9s %9s %9s | %10s %11s %11s\n", "sync_ms", "trials", "frames",
              "onset_p50", "onset_p99", "onset_max", "all_p50", "all_p99", "all_max", "syncs_loop",
              "syncs_setup", "syncs_other");
  for (const int delay_ms : delays) {
    rn::HeadlessOptions ho;
    ho.pace = realtime ? rn::Pace::realtime : rn::Pace::fast;
    ho.no_gpu = true;
    ho.refresh_hz = p.refresh_hz;
    auto made = rn::HeadlessDevices::create(ho, rn::standing_at(rn::nominal_calibration(p.session_settings())));
    if (!made) {
      std::fprintf(stderr, "headless display: %s\n", made.error().message.c_str());
      return 1;
    }
    auto& headless = made.value();
    TimingDisplay backend(*headless.display);
    rn::RunOptions o;
    o.participant = "B01";
    o.observer = rn::ObserverParams{};
    o.drawing = rn::FrameDrawing::none;
    o.lossless_logging = !realtime;
    std::string file = "delay_";
    file += std::to_string(delay_ms);
    file += ".sqlite";
    const auto db = (tmp / file).string();
    vfs::set_sync_delay(std::chrono::milliseconds(delay_ms));
    vfs::reset();
    const auto result = rn::run_session(p, text.str(), db, o, {&backend, headless.poses.get(), {}}, headless.clock());
    vfs::set_sync_delay(std::chrono::microseconds(0));
    if (!result) {
      std::fprintf(stderr, "%s\n", result.error().message.c_str());
      return 1;
    }
    const auto& s = result.value();
    const auto frame_thread = std::this_thread::get_id();
    const auto own = vfs::syncs_from(frame_thread);
    std::printf("%8d %7lld %7lld | %9.3f %9.3f %9.3f | %9.3f %9.3f %9.3f | %10lld %11lld %11lld\n", delay_ms,
                static_cast<long long>(s.trials_completed), static_cast<long long>(s.frames),
                quantile(backend.onset_ms, 0.5), quantile(backend.onset_ms, 0.99),
                quantile(backend.onset_ms, 1.0), quantile(backend.all_ms, 0.5), quantile(backend.all_ms, 0.99),
                quantile(backend.all_ms, 1.0), static_cast<long long>(backend.loop_syncs),
                static_cast<long long>(own - backend.loop_syncs), static_cast<long long>(vfs::total_syncs() - own));
  }
  std::printf("\nloop times in ms (runner work from frame hand-out to the next frame request; GPU excluded);\n"
              "syncs: disk syncs issued by the frame thread within the frame loop, by the same thread\n"
              "before the first frame and after the last (creating and closing the session), and by\n"
              "the logger's writer thread.\n"
              "A 90 Hz frame has 11.1 ms; an onset frame that waits on the disk is shown late.\n");
  std::filesystem::remove_all(tmp);
  return 0;
}
