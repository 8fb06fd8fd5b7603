// The reader thread with a recorded report sequence standing in for the
// device (no HID devices exist on CI machines): events arrive in order,
// timestamped on the given clock, and the end of the recording reads as an
// unplug that releases held responses and reports a message.
#include "curvlab/harness/devices/reader.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <vector>

namespace {

using namespace curvlab::harness::devices;

// Replays reports, then fails like an unplugged device.
class RecordedSource final : public ReportSource {
 public:
  explicit RecordedSource(std::vector<std::vector<std::uint8_t>> reports)
      : reports_(std::move(reports)) {}
  curvlab::harness::Result<std::size_t> read(std::span<std::uint8_t> buffer, int) override {
    if (next_ >= reports_.size())
      return curvlab::harness::Error{curvlab::harness::Error::Kind::device,
                                     "button box stopped responding: No such device"};
    const auto& r = reports_[next_++];
    std::copy(r.begin(), r.end(), buffer.begin());
    return r.size();
  }
  std::string label() const override { return "recorded button box"; }

 private:
  std::vector<std::vector<std::uint8_t>> reports_;
  std::size_t next_ = 0;
};

// Each reading advances by 1 ms, so timestamps are known exactly.
class StepClock final : public curvlab::harness::io::Clock {
 public:
  std::int64_t now_ns() const override { return (++t_) * 1'000'000; }
 private:
  mutable std::atomic<std::int64_t> t_{0};
};

TEST(DeviceReader, QueuesTimestampedEventsAndReportsUnplug) {
  DeviceMapping mapping;
  mapping.name = "box";
  mapping.bindings = {{"yes", BitBinding{0, 0}}, {"no", BitBinding{0, 1}}};
  EventQueue queue;
  StepClock clock;
  {
    DeviceReader reader(std::make_unique<RecordedSource>(std::vector<std::vector<std::uint8_t>>{
                            {0x01}, {0x00}, {0x02}}),
                        mapping, clock, queue);
    std::vector<DeviceEvent> events;
    // Blocking pops without a time assertion: each waits as long as needed
    // (a generous bound only guards against a hung test).
    while (events.size() < 5) {
      auto e = queue.pop_wait(std::chrono::seconds(30));
      ASSERT_TRUE(e.has_value());
      events.push_back(std::move(*e));
    }
    EXPECT_EQ(events[0].response.response, "yes");
    EXPECT_EQ(events[0].response.edge, ResponseEvent::Edge::Down);
    EXPECT_EQ(events[0].t_ns, 1'000'000);
    EXPECT_EQ(events[1].response.response, "yes");
    EXPECT_EQ(events[1].response.edge, ResponseEvent::Edge::Up);
    EXPECT_EQ(events[1].t_ns, 2'000'000);
    EXPECT_EQ(events[2].response.response, "no");
    EXPECT_EQ(events[2].t_ns, 3'000'000);
    // Unplug: the held "no" is released, then the disconnection is reported.
    EXPECT_EQ(events[3].response.response, "no");
    EXPECT_EQ(events[3].response.edge, ResponseEvent::Edge::Up);
    EXPECT_EQ(events[4].kind, DeviceEvent::Kind::Disconnected);
    EXPECT_EQ(events[4].device, "recorded button box");
    EXPECT_NE(events[4].message.find("stopped responding"), std::string::npos);
    EXPECT_NE(events[4].message.find("reconnect it and resume"), std::string::npos);
  }  // the destructor joins the finished thread
  EXPECT_FALSE(queue.try_pop().has_value());
}

// A source that never delivers: the destructor must still stop the thread.
class SilentSource final : public ReportSource {
 public:
  curvlab::harness::Result<std::size_t> read(std::span<std::uint8_t>, int) override {
    return std::size_t{0};
  }
  std::string label() const override { return "silent"; }
};

TEST(DeviceReader, DestructorStopsAReaderThatIsStillReading) {
  EventQueue queue;
  curvlab::harness::io::SteadyClock clock;
  {
    DeviceReader reader(std::make_unique<SilentSource>(), DeviceMapping{}, clock, queue, 1);
    EXPECT_FALSE(reader.finished());
  }
  EXPECT_FALSE(queue.try_pop().has_value());
}

TEST(HidLibrary, EnumerationWithoutDevicesIsEmptyNotAnError) {
  auto lib = HidLibrary::open();
  ASSERT_TRUE(lib) << lib.error().message;
  // Two references at once are fine (hidapi's state is counted).
  auto second = HidLibrary::open();
  ASSERT_TRUE(second);
  for (const auto& d : lib.value().enumerate()) EXPECT_FALSE(d.path.empty());
}

}  // namespace

namespace {

TEST(HidDevice, OpeningAMissingDeviceIsAnErrorNamingIt) {
  curvlab::harness::devices::HidDeviceInfo info;
  info.vendor_id = 0x046d;
  info.product_id = 0xc216;
  info.product = "Dual Action";
  info.path = "/dev/hidraw-curvlab-missing";
  auto opened = curvlab::harness::devices::HidDevice::open(info);
  ASSERT_FALSE(opened);
  EXPECT_EQ(opened.error().kind, curvlab::harness::Error::Kind::device);
  const std::string msg = opened.error().message;
  EXPECT_NE(msg.find("cannot open 046d:c216 Dual Action"), std::string::npos) << msg;
  EXPECT_NE(msg.find("/dev/hidraw-curvlab-missing"), std::string::npos) << msg;
}

}  // namespace
