// What the Lab Streaming Layer's outlets cost the participant's frame
// (docs/lsl.md, "Cost"): whole realtime headless sessions of the demo
// protocol (nothing drawn, so that the runner's own work is what is
// measured), alternately without and with outlets, each outlet read by an
// inlet of this program as LabRecorder would. The runner's CPU time per
// frame (tracking, trial state, logging, and with outlets the markers' and
// poses' hand-over) is compared in one run. With outlets, the session waits
// for this program's inlets before its first frame; the headless display
// then runs the frames it missed meanwhile without pausing (more frames,
// the same work each).
//
//   bench_lsl_cost [rounds]        (default 2 rounds of off/on)
//
// Keeps liblsl on the loopback unless LSLAPICFG names a configuration.
#include "curvlab/harness/lsl/session_streams.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/headless.hpp"
#include "curvlab/harness/runner/session.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <lsl_cpp.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>

namespace rn = curvlab::harness::runner;
namespace pr = curvlab::harness::protocol;
namespace lsl_streams = curvlab::harness::lsl;

namespace {

// Subscribes to every curvlab stream that appears and pulls all it sends,
// until told to stop; counts what it received.
class Reader {
 public:
  Reader() : thread_([this] { run(); }) {}
  ~Reader() {
    stop_ = true;
    thread_.join();
  }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;
  [[nodiscard]] long long samples() const { return samples_.load(); }

 private:
  void run() {
    std::vector<std::unique_ptr<lsl::stream_inlet>> inlets;
    std::set<std::string> seen;
    std::vector<float> values;
    std::vector<std::string> text;
    auto last_resolve = std::chrono::steady_clock::now() - std::chrono::seconds(1);
    while (!stop_) {
      if (std::chrono::steady_clock::now() - last_resolve > std::chrono::milliseconds(200)) {
        // A second's search: liblsl's unicast wave reaches one outlet per
        // process; its multicast waves, which come later, reach them all.
        for (const auto& info : lsl::resolve_streams(1.0))
          if (info.source_id().starts_with("curvlab-") && seen.insert(info.uid()).second) {
            inlets.push_back(std::make_unique<lsl::stream_inlet>(info));
            inlets.back()->open_stream(5.0);
          }
        last_resolve = std::chrono::steady_clock::now();
      }
      bool any = false;
      for (auto& in : inlets) {
        const bool strings = in->get_channel_count() == 1;
        while ((strings ? in->pull_sample(text, 0.0) : in->pull_sample(values, 0.0)) != 0.0) {
          ++samples_;
          any = true;
        }
      }
      if (!any) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  std::atomic<bool> stop_{false};
  std::atomic<long long> samples_{0};
  std::thread thread_;
};

}  // namespace

int main(int argc, char** argv) {
  const int rounds = argc > 1 ? std::max(1, std::atoi(argv[1])) : 2;
  const auto tmp = std::filesystem::temp_directory_path() / "curvlab_bench_lsl";
  std::filesystem::remove_all(tmp);
  std::filesystem::create_directories(tmp);
  if (std::getenv("LSLAPICFG") == nullptr) {
    const auto cfg = (tmp / "lsl_api.cfg").string();
    std::ofstream(cfg) << "[ports]\nIPv6 = disable\n[multicast]\nResolveScope = machine\nInterfaces = {127.0.0.1}\n"
                       << "[lab]\nKnownPeers = {127.0.0.1}\n";
    setenv("LSLAPICFG", cfg.c_str(), 1);
  }
  const std::string path = CURVLAB_SOURCE_DIR "/protocols/demo.toml";
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  auto loaded = pr::load_protocol_text(text.str(), path);
  if (!loaded) {
    std::fprintf(stderr, "%s does not load\n", path.c_str());
    return 1;
  }
  const auto& p = *loaded;
  Reader reader;
  std::printf("%-8s %8s %11s %11s %11s %10s %9s\n", "outlets", "frames", "cpu_med_ms", "cpu_p95_ms", "session_s",
              "received", "dropped");
  double med[2] = {0.0, 0.0}, p95[2] = {0.0, 0.0};
  for (int round = 0; round < rounds; ++round)
    for (const bool on : {false, true}) {
      rn::HeadlessOptions ho;
      ho.pace = rn::Pace::realtime;
      ho.refresh_hz = p.refresh_hz;
      ho.no_gpu = true;
      auto made = rn::HeadlessDevices::create(ho, rn::standing_at(rn::nominal_calibration(p.session_settings())));
      if (!made) {
        std::fprintf(stderr, "%s\n", made.error().message.c_str());
        return 1;
      }
      const auto& devices = made.value();
      std::unique_ptr<curvlab::harness::io::SessionStreams> streams;
      if (on) {
        lsl_streams::StreamOptions so;
        so.wait_for_recorder = std::chrono::seconds(10);
        auto opened = lsl_streams::open(so, devices.clock());
        if (!opened) {
          std::fprintf(stderr, "%s\n", opened.error().message.c_str());
          return 1;
        }
        streams = std::move(opened).value();
      }
      rn::RunOptions o;
      o.participant = "B01";
      o.observer = rn::ObserverParams{};
      o.drawing = rn::FrameDrawing::none;
      o.lossless_logging = false;
      o.streams = streams.get();
      const long long before = reader.samples();
      const auto db = (tmp / ("run" + std::to_string(round) + (on ? "on" : "off") + ".sqlite")).string();
      const auto result = rn::run_session(p, text.str(), db, o, devices.station(), devices.clock());
      streams.reset();
      std::this_thread::sleep_for(std::chrono::milliseconds(2500));  // the reader catches up (its search takes 1 s)
      if (!result) {
        std::fprintf(stderr, "%s\n", result.error().message.c_str());
        return 1;
      }
      const auto& s = result.value();
      med[on ? 1 : 0] += s.frame_cpu_median_ms / rounds;
      p95[on ? 1 : 0] += s.frame_cpu_p95_ms / rounds;
      std::printf("%-8s %8lld %11.4f %11.4f %11.2f %10lld %9llu\n", on ? "on" : "off",
                  static_cast<long long>(s.frames), s.frame_cpu_median_ms, s.frame_cpu_p95_ms, s.session_s,
                  reader.samples() - before, static_cast<unsigned long long>(s.samples_dropped));
    }
  std::printf("\nmean of %d rounds: median %.4f ms off, %.4f ms on (%+.4f ms); p95 %.4f ms off, %.4f ms on "
              "(%+.4f ms)\n",
              rounds, med[0], med[1], med[1] - med[0], p95[0], p95[1], p95[1] - p95[0]);
  std::printf("frame budget at 90 Hz: 11.1 ms; liblsl %s\n", lsl_streams::library_version().c_str());
  std::filesystem::remove_all(tmp);
  return 0;
}
