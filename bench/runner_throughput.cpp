// The session runner's cost: per-frame harness CPU time at the protocol's
// 90 Hz (tracking, phase logic, scene update, render planning and command
// recording, log enqueue; the GPU's own time excluded), and how many trials
// per second a headless simulated session completes in simulated time.
//
//   bench_runner_throughput [realtime_seconds]
//
// Each row is one whole headless session of a protocol in protocols/.
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/headless.hpp"
#include "curvlab/harness/runner/session.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace rn = curvlab::harness::runner;
namespace pr = curvlab::harness::protocol;

namespace {

struct Row {
  const char* protocol;
  rn::Pace pace;
  rn::FrameDrawing drawing;
};

}  // namespace

int main(int argc, char** argv) {
  (void)argc;
  (void)argv;
  const std::string dir = CURVLAB_SOURCE_DIR "/protocols/";
  const auto tmp = std::filesystem::temp_directory_path() / "curvlab_bench_runner";
  std::filesystem::remove_all(tmp);
  std::filesystem::create_directories(tmp);
  const Row rows[] = {
      {"demo", rn::Pace::realtime, rn::FrameDrawing::all},
      {"demo", rn::Pace::fast, rn::FrameDrawing::all},
      {"demo", rn::Pace::fast, rn::FrameDrawing::onset},
      {"demo", rn::Pace::fast, rn::FrameDrawing::none},
      {"proposed_study", rn::Pace::fast, rn::FrameDrawing::onset},
      {"proposed_study", rn::Pace::fast, rn::FrameDrawing::none},
      {"stick_pse_staircase", rn::Pace::fast, rn::FrameDrawing::none},
  };
  std::printf("%-20s %-8s %-6s %7s %8s %9s %8s %11s %11s %10s\n", "protocol", "pace", "draw", "trials",
              "frames", "session_s", "wall_s", "cpu_med_ms", "cpu_p95_ms", "trials/s");
  int n = 0;
  for (const auto& row : rows) {
    const std::string path = dir + row.protocol + ".toml";
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    auto loaded = pr::load_protocol_text(ss.str(), path);
    if (!loaded) {
      std::fprintf(stderr, "%s does not load\n", path.c_str());
      return 1;
    }
    const auto& p = *loaded;
    rn::HeadlessOptions ho;
    ho.pace = row.pace;
    ho.refresh_hz = p.refresh_hz;
    ho.width_px = static_cast<std::uint32_t>(p.resolution_width);
    ho.height_px = static_cast<std::uint32_t>(p.resolution_height);
    auto made = rn::HeadlessDevices::create(ho, rn::standing_at(rn::nominal_calibration(p.session_settings())));
    if (!made) {
      std::fprintf(stderr, "%s\n", made.error().message.c_str());
      return 1;
    }
    const auto& devices = made.value();
    rn::RunOptions o;
    o.participant = "B01";
    o.participant_number = 1;
    o.observer = rn::ObserverParams{};
    o.drawing = row.drawing;
    o.lossless_logging = row.pace == rn::Pace::fast;
    const auto db = (tmp / ("run" + std::to_string(n++) + ".sqlite")).string();
    const auto result = rn::run_session(p, ss.str(), db, o, devices.station(), devices.clock());
    if (!result) {
      std::fprintf(stderr, "%s\n", result.error().message.c_str());
      return 1;
    }
    const auto& s = result.value();
    const char* draw = row.drawing == rn::FrameDrawing::all ? "all" : row.drawing == rn::FrameDrawing::onset ? "onset" : "none";
    std::printf("%-20s %-8s %-6s %7lld %8lld %9.1f %8.2f %11.4f %11.4f %10.1f\n", row.protocol,
                row.pace == rn::Pace::fast ? "fast" : "realtime", draw,
                static_cast<long long>(s.trials_completed), static_cast<long long>(s.frames), s.session_s,
                s.wall_s, s.frame_cpu_median_ms, s.frame_cpu_p95_ms,
                static_cast<double>(s.trials_completed) / s.wall_s);
  }
  std::printf("\nframe budget at 90 Hz: 11.1 ms; target for the harness's CPU share: median <= 0.5 ms\n");
  std::filesystem::remove_all(tmp);
  return 0;
}
