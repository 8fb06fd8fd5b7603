#include "curvlab/harness/devices/responses.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>

namespace curvlab::harness::devices {

using harness::Error;

namespace {

std::string connected_list(const std::vector<HidDeviceInfo>& devices) {
  if (devices.empty()) return "no HID devices are connected (or none is readable: see docs/devices.md, Permissions)";
  std::string out = "connected: ";
  for (std::size_t i = 0; i < devices.size(); ++i) out += (i ? "; " : "") + describe(devices[i]);
  return out;
}

void add_reach(harness::io::Reach& r, const DeviceMapping& mapping) {
  r.kind = harness::io::SourceKind::hid;
  for (const auto& b : mapping.bindings) {
    r.buttons.push_back(b.response);
    const harness::io::Intents intents = response_intents(b.response);
    r.intents |= intents;
    if (intents.has(harness::io::Intent::continue_page) && r.continue_phrase.empty())
      r.continue_phrase = "press the continue button of " + mapping.name;
  }
}

}  // namespace

harness::io::Intents response_intents(const std::string& response) {
  if (response == "continue") return {harness::io::Intent::continue_page};
  return {};
}

harness::io::InputEvent response_input(std::int64_t t_ns, const std::string& device, std::string response,
                                       bool pressed) {
  harness::io::InputEvent in;
  in.t_ns = t_ns;
  in.source = {harness::io::SourceKind::hid, device};
  in.intents = response_intents(response);
  in.control = {harness::io::ControlKind::button, std::move(response)};
  in.pressed = pressed;
  return in;
}

harness::io::Reach mapping_reach(const MappingFile& file) {
  harness::io::Reach r;
  r.kind = harness::io::SourceKind::hid;
  for (const auto& m : file.devices) add_reach(r, m);
  return r;
}

harness::Result<std::unique_ptr<HidResponses>> HidResponses::open(const MappingFile& file, const harness::io::Clock& clock) {
  auto library = HidLibrary::open();
  if (!library) return library.error();
  const auto connected = library->enumerate();
  std::vector<std::pair<std::unique_ptr<ReportSource>, DeviceMapping>> sources;
  for (const auto& mapping : file.devices) {
    const auto found = std::find_if(connected.begin(), connected.end(),
                                    [&](const HidDeviceInfo& d) { return mapping.match.matches(d); });
    if (found == connected.end())
      return Error{Error::Kind::device, file.file + ": the response device '" + mapping.name +
                                            "' is not connected; " + connected_list(connected)};
    auto device = HidDevice::open(*found);
    if (!device)
      return Error{Error::Kind::device,
                   file.file + ": the response device '" + mapping.name + "': " + device.error().message};
    sources.emplace_back(std::make_unique<HidDevice>(std::move(device).value()), mapping);
  }
  return read(std::move(sources), clock);
}

std::unique_ptr<HidResponses> HidResponses::read(
    std::vector<std::pair<std::unique_ptr<ReportSource>, DeviceMapping>> sources, const harness::io::Clock& clock) {
  std::unique_ptr<HidResponses> out(new HidResponses());
  for (auto& [source, mapping] : sources) {
    out->names_.emplace_back(source->label(), mapping.name);
    add_reach(out->reach_, mapping);
    out->readers_.push_back(std::make_unique<DeviceReader>(std::move(source), std::move(mapping), clock, out->queue_));
  }
  return out;
}

HidResponses::~HidResponses() = default;  // the readers (declared after the queue) stop and join first

harness::io::Signal HidResponses::poll(std::vector<harness::io::InputEvent>& out) {
  harness::io::Signal signal = harness::io::Signal::none;
  while (auto e = queue_.try_pop()) {
    if (e->kind == DeviceEvent::Kind::Disconnected) {
      message_ = e->message;
      std::fprintf(stderr, "curvlab: %s\n", message_.c_str());
      signal = harness::io::Signal::pause;
      continue;
    }
    const auto name = std::find_if(names_.begin(), names_.end(), [&](const auto& n) { return n.first == e->device; });
    out.push_back(response_input(e->t_ns, name != names_.end() ? name->second : e->device, e->response.response,
                                 e->response.edge == ResponseEvent::Edge::Down));
  }
  return signal;
}

harness::Result<std::size_t> RecordedReports::read(std::span<std::uint8_t> buffer, int timeout_ms) {
  const std::int64_t until = clock_.now_ns() + std::int64_t{timeout_ms} * 1'000'000;
  if (next_ >= reports_.size()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(timeout_ms));
    return std::size_t{0};
  }
  const Report& r = reports_[next_];
  for (;;) {
    const std::int64_t now = clock_.now_ns();
    if (now >= r.t_ns) break;
    if (now >= until) return std::size_t{0};
    std::this_thread::sleep_for(std::chrono::nanoseconds(std::min<std::int64_t>(r.t_ns - now, 1'000'000)));
  }
  ++next_;
  const std::size_t n = std::min(buffer.size(), r.bytes.size());
  std::copy_n(r.bytes.begin(), n, buffer.begin());
  return n;
}

}  // namespace curvlab::harness::devices
