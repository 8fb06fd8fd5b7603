// The headless devices, the embedded default (DESIGN.md §6): an offscreen
// display (a Vulkan renderer on lavapipe or a GPU) in simulated time (as fast
// as the machine goes) or real time at the protocol's refresh rate, and lab
// poses from a generated or recorded trajectory. The simulated observer
// answers (session.hpp, RunOptions::observer).
#pragma once

#include "curvlab/geometry/calibration.hpp"
#include "curvlab/geometry/trajectory.hpp"
#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/io/display.hpp"
#include "curvlab/harness/io/pose_source.hpp"
#include "curvlab/harness/io/station.hpp"
#include "curvlab/harness/result.hpp"

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>

namespace curvlab::harness::runner {

// Simulated time: advanced by the headless display frame by frame.
class SimulatedClock final : public io::Clock {
 public:
  explicit SimulatedClock(std::int64_t start_ns = 0) : now_(start_ns) {}
  [[nodiscard]] std::int64_t now_ns() const override { return now_.load(std::memory_order_acquire); }
  void set(std::int64_t t_ns) { now_.store(t_ns, std::memory_order_release); }

 private:
  std::atomic<std::int64_t> now_;
};

enum class Pace { fast, realtime };

struct HeadlessOptions {
  Pace pace = Pace::fast;
  double refresh_hz = 90.0;
  std::uint32_t width_px = 1024;  // per eye
  std::uint32_t height_px = 1024;
  bool software = false;  // lavapipe even with a GPU
  // Samples per pixel requested (clamped to the device); nullopt: the
  // device's automatic count (renderer::automatic_msaa).
  std::optional<std::uint32_t> msaa;
  std::int64_t start_ns = 0;  // the session clock at the first frame
  // No renderer at all (predictions, tests of the state machine): submit()
  // plans nothing and returns zero counts.
  bool no_gpu = false;
};

// The offscreen display. A failing Vulkan call in submit() or save_frame() (a
// lost device) throws DeviceFailure naming it. Owns its Vulkan context,
// renderer and target; not thread-safe. A frame is predicted to be shown one
// period after it begins.
class HeadlessDisplay final : public io::Display {
 public:
  // No Vulkan device: an Error of kind `device`; a bad option: `usage`.
  static Result<std::unique_ptr<HeadlessDisplay>> create(const HeadlessOptions& options);
  // Waits for the GPU; never throws, a lost device included.
  ~HeadlessDisplay() override;

  // The clock the session must use: simulated (fast) or steady (real time).
  [[nodiscard]] const io::Clock& clock() const;
  // The session clock when the first frame begins: where a trajectory
  // (TrajectoryPoses) starts.
  [[nodiscard]] std::int64_t first_ns() const;
  [[nodiscard]] std::int64_t period_ns() const;

  [[nodiscard]] io::DisplayInfo info() const override;
  std::optional<io::FrameTiming> begin_frame() override;
  renderer::StereoRig rig(const io::FrameTiming& frame, double ipd_m) override;
  renderer::FrameStats submit(const renderer::Scene& scene, const renderer::FrameDescription& frame,
                              const io::Overlay& overlay, bool draw) override;
  std::vector<std::string> save_frame(const std::string& stem) override;

  struct Impl;

 private:
  explicit HeadlessDisplay(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

struct TrajectoryOptions {
  // Lab poses; looped when the session outlasts it. Empty: the participant
  // stands in front of edge 0 of `table` and sways a little.
  geometry::Trajectory trajectory;
  geometry::PhysicalTableFit table;  // the calibrated physical table
  double eye_height_m = 1.55;
  // The session clock at the trajectory's start, and the frame period (the
  // gap between its last sample and the first when it loops).
  std::int64_t start_ns = 0;
  std::int64_t period_ns = 11'111'111;
};

// The default standing participant (no trajectory) at `table`.
inline TrajectoryOptions standing_at(const geometry::PhysicalTableFit& table) {
  TrajectoryOptions o;
  o.table = table;
  return o;
}

// Poses from a generated or recorded trajectory: the sample at or before
// the frame's display time.
class TrajectoryPoses final : public io::PoseSource {
 public:
  explicit TrajectoryPoses(TrajectoryOptions options) : options_(std::move(options)) {}
  geometry::LabFrame poses(const io::FrameTiming& frame) override;

 private:
  TrajectoryOptions options_;
};

// The headless display with poses from a trajectory, as one station (the
// CLI's headless runs, tests and benchmarks). The trajectory starts at the
// display's first frame and loops with its frame period.
struct HeadlessDevices {
  std::unique_ptr<HeadlessDisplay> display;
  std::unique_ptr<TrajectoryPoses> poses;

  static Result<HeadlessDevices> create(const HeadlessOptions& display, TrajectoryOptions trajectory);
  [[nodiscard]] io::Station station() const { return {display.get(), poses.get(), {}}; }
  [[nodiscard]] const io::Clock& clock() const { return display->clock(); }
};

// The default standing pose with sway at time t (also used by tests).
geometry::LabFrame standing_pose(const geometry::PhysicalTableFit& table, double eye_height_m,
                                 std::int64_t t_ns);

}  // namespace curvlab::harness::runner
