// Reading a response device on its own thread: each report is timestamped on
// the session clock as soon as it is read, parsed, and its events queued for
// the session loop. Unplugging arrives as an event, so the session can pause
// with a message instead of waiting forever for a button.
#pragma once

#include "curvlab/harness/devices/hid.hpp"
#include "curvlab/harness/devices/report_parser.hpp"
#include "curvlab/harness/io/clock.hpp"

#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

namespace curvlab::harness::devices {

struct DeviceEvent {
  enum class Kind { Response, Disconnected };
  Kind kind = Kind::Response;
  ResponseEvent response;  // Kind::Response
  std::string device;      // label of the source
  std::string message;     // Kind::Disconnected: what happened, for the experimenter
  std::int64_t t_ns = 0;
};

// Multi-producer, multi-consumer FIFO. Thread-safe.
class EventQueue {
 public:
  void push(DeviceEvent event);
  std::optional<DeviceEvent> try_pop();
  // Blocks until an event arrives or `timeout` passes.
  std::optional<DeviceEvent> pop_wait(std::chrono::milliseconds timeout);

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<DeviceEvent> events_;
};

// Owns one ReportSource and the thread that reads it; the destructor stops
// and joins the thread (it notices within poll_ms). Move-free: the thread
// holds `this`. The queue and clock are borrowed and must outlive the reader.
class DeviceReader {
 public:
  DeviceReader(std::unique_ptr<ReportSource> source, DeviceMapping mapping, const harness::io::Clock& clock,
               EventQueue& queue, int poll_ms = 50);
  DeviceReader(const DeviceReader&) = delete;
  DeviceReader& operator=(const DeviceReader&) = delete;
  ~DeviceReader();

  // True once the thread has ended (source disconnected or reader stopped).
  [[nodiscard]] bool finished() const { return finished_.load(); }

 private:
  void run();
  std::unique_ptr<ReportSource> source_;
  ReportParser parser_;
  const harness::io::Clock& clock_;
  EventQueue& queue_;
  int poll_ms_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> finished_{false};
  std::thread thread_;  // last: starts after every member above exists
};

}  // namespace curvlab::harness::devices
