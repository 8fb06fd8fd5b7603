// HID devices as one of a session's response sources (io/response_source.hpp):
// each device is read on its own thread (reader.hpp), its reports turned into
// named responses by its mapping file and timestamped on the session clock
// the moment they are read; the session takes them each frame. A response's
// name is one a judgement's `buttons` list (docs/protocols.md). An unplugged
// device pauses the session with a message for the experimenter.
#pragma once

#include "curvlab/harness/devices/mapping.hpp"
#include "curvlab/harness/devices/reader.hpp"
#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/io/response_source.hpp"
#include "curvlab/harness/result.hpp"

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace curvlab::harness::devices {

// What the devices of a mapping file can press: each binding's response name.
harness::io::Reach mapping_reach(const MappingFile& file);

// What a mapping's response means to a session by its name: a response
// named "continue" continues a page; the others mean nothing by themselves
// (they answer through the protocol's `buttons`).
harness::io::Intents response_intents(const std::string& response);
// A response of the device named `device` in its mapping file as an input
// (device "hid:<device>"): a button, pressed or released.
harness::io::InputEvent response_input(std::int64_t t_ns, const std::string& device, std::string response,
                                       bool pressed);

class HidResponses final : public harness::io::ResponseSource {
 public:
  // For every [[device]] of `file`, opens the first connected HID device it
  // matches. One that matches none, or cannot be opened: an Error of kind
  // `device` naming the mapping entry, the file and what is connected.
  static harness::Result<std::unique_ptr<HidResponses>> open(const MappingFile& file, const harness::io::Clock& clock);
  // Reads the given sources (an open device, or a recorded report stream)
  // through their mappings.
  static std::unique_ptr<HidResponses> read(std::vector<std::pair<std::unique_ptr<ReportSource>, DeviceMapping>> sources,
                                            const harness::io::Clock& clock);
  HidResponses(const HidResponses&) = delete;
  HidResponses& operator=(const HidResponses&) = delete;
  // Stops and joins every reader thread.
  ~HidResponses() override;

  // Presses and releases since the last call (each device by its mapping's
  // name, or its label when it has none);
  // pause when a device went away (its message on stderr and in message()).
  harness::io::Signal poll(std::vector<harness::io::InputEvent>& out) override;
  // The mappings' response names; pages continue on a binding named
  // "continue" (or on any answer the protocol binds to these buttons).
  [[nodiscard]] harness::io::Reach reach() const override { return reach_; }
  // The last unplug message ("" none).
  [[nodiscard]] const std::string& message() const { return message_; }

 private:
  HidResponses() = default;
  EventQueue queue_;  // first: the readers push into it until they are joined
  std::vector<std::unique_ptr<DeviceReader>> readers_;
  std::vector<std::pair<std::string, std::string>> names_;  // source label → mapping name
  std::string message_;
  harness::io::Reach reach_;
};

// A recorded report stream replayed on the session clock: each report is
// handed to the reader once the clock has reached its time. After the last
// one the device stays connected and silent. For tests and for checking a
// mapping against a recording of the real device.
class RecordedReports final : public ReportSource {
 public:
  struct Report {
    std::int64_t t_ns = 0;  // session clock
    std::vector<std::uint8_t> bytes;
  };
  RecordedReports(std::vector<Report> reports, const harness::io::Clock& clock, std::string label)
      : reports_(std::move(reports)), clock_(clock), label_(std::move(label)) {}
  harness::Result<std::size_t> read(std::span<std::uint8_t> buffer, int timeout_ms) override;
  [[nodiscard]] std::string label() const override { return label_; }

 private:
  std::vector<Report> reports_;  // in time order
  std::size_t next_ = 0;
  const harness::io::Clock& clock_;
  std::string label_;
};

}  // namespace curvlab::harness::devices
