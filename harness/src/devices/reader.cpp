#include "curvlab/harness/devices/reader.hpp"

#include <array>

namespace curvlab::harness::devices {

void EventQueue::push(DeviceEvent event) {
  {
    const std::lock_guard lock(mutex_);
    events_.push_back(std::move(event));
  }
  ready_.notify_one();
}

std::optional<DeviceEvent> EventQueue::try_pop() {
  const std::lock_guard lock(mutex_);
  if (events_.empty()) return std::nullopt;
  DeviceEvent e = std::move(events_.front());
  events_.pop_front();
  return e;
}

std::optional<DeviceEvent> EventQueue::pop_wait(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!ready_.wait_for(lock, timeout, [this] { return !events_.empty(); })) return std::nullopt;
  DeviceEvent e = std::move(events_.front());
  events_.pop_front();
  return e;
}

DeviceReader::DeviceReader(std::unique_ptr<ReportSource> source, DeviceMapping mapping,
                           const harness::io::Clock& clock, EventQueue& queue, int poll_ms)
    : source_(std::move(source)),
      parser_(std::move(mapping)),
      clock_(clock),
      queue_(queue),
      poll_ms_(poll_ms),
      thread_([this] { run(); }) {}

DeviceReader::~DeviceReader() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

void DeviceReader::run() {
  // 64 bytes is the largest full-speed USB interrupt report; one more for a
  // report ID byte.
  std::array<std::uint8_t, 65> buffer{};
  const std::string label = source_->label();
  while (!stop_.load()) {
    auto result = source_->read(buffer, poll_ms_);
    // Timestamp first: the report reached user space just now. (USB polling
    // adds up to one bInterval, typically 1–8 ms, before this; docs/devices.md.)
    const std::int64_t t_ns = clock_.now_ns();
    if (!result) {
      for (auto& e : parser_.release_all(t_ns))
        queue_.push({DeviceEvent::Kind::Response, std::move(e), label, "", t_ns});
      DeviceEvent gone;
      gone.kind = DeviceEvent::Kind::Disconnected;
      gone.device = label;
      gone.message = result.error().message + "; reconnect it and resume the session";
      gone.t_ns = t_ns;
      queue_.push(std::move(gone));
      break;
    }
    const std::size_t n = result.value();
    if (n == 0) continue;
    for (auto& e : parser_.parse(std::span<const std::uint8_t>(buffer.data(), n), t_ns))
      queue_.push({DeviceEvent::Kind::Response, std::move(e), label, "", t_ns});
  }
  finished_.store(true);
}

}  // namespace curvlab::harness::devices
