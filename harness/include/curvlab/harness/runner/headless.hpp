// The headless backend, the embedded default (DESIGN.md §6): an offscreen
// Vulkan renderer (lavapipe, or a GPU), lab poses from a generated or
// recorded trajectory, and either simulated time (as fast as the machine
// goes) or real time at the protocol's refresh rate.
#pragma once

#include "curvlab/geometry/calibration.hpp"
#include "curvlab/geometry/trajectory.hpp"
#include "curvlab/harness/devices/clock.hpp"
#include "curvlab/harness/runner/backend.hpp"

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>

namespace curvlab::harness::runner {

// Simulated time: advanced by the headless backend frame by frame.
class SimulatedClock final : public devices::Clock {
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
  std::uint32_t msaa = 4;  // samples per pixel requested (clamped to the device)
  // Lab poses; looped when the session outlasts it. Empty: the participant
  // stands in front of edge 0 of `table` and sways a little.
  geometry::Trajectory trajectory;
  geometry::PhysicalTableFit table;  // the calibrated physical table
  double eye_height_m = 1.55;
  std::int64_t start_ns = 0;  // the session clock at the first frame
  // No renderer at all (predictions, tests of the state machine): submit()
  // plans nothing and returns zero counts.
  bool no_gpu = false;
};

// A failing Vulkan call in submit() or save_frame() (a lost device) throws
// BackendFailure naming it. Owns its Vulkan context, renderer and target;
// not thread-safe.
class HeadlessBackend final : public Backend {
 public:
  // No Vulkan device: an Error of kind `device`; a bad option: `usage`.
  static Result<std::unique_ptr<HeadlessBackend>> create(const HeadlessOptions& options);
  // Waits for the GPU; never throws, a lost device included.
  ~HeadlessBackend() override;

  // The clock the session must use: simulated (fast) or steady (real time).
  [[nodiscard]] const devices::Clock& clock() const;

  [[nodiscard]] BackendInfo info() const override;
  std::optional<FrameTiming> begin_frame() override;
  geometry::LabFrame poses(const FrameTiming& frame) override;
  BackendSignal poll_input(std::vector<InputEvent>& out) override;
  renderer::StereoRig rig(const FrameTiming& frame, double ipd_m) override;
  renderer::FrameStats submit(const renderer::Scene& scene, const renderer::FrameDescription& frame,
                              const Overlay& overlay, bool draw) override;
  std::vector<std::string> save_frame(const std::string& stem) override;

  struct Impl;

 private:
  explicit HeadlessBackend(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The default standing pose with sway at time t (also used by tests).
geometry::LabFrame standing_pose(const geometry::PhysicalTableFit& table, double eye_height_m,
                                 std::int64_t t_ns);

}  // namespace curvlab::harness::runner
