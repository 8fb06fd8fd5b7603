// libFuzzer entry point for the HID mapping file (built only with
// -DCURVLAB_FUZZ=ON and clang; run by bench/fuzz_mapping.sh). Any input must
// give either a mapping or one "file:line:column: field: message" error —
// never a crash, hang or sanitizer report — and an accepted mapping must
// drive the report parser: presses and releases alternate per binding, and
// release_all() leaves nothing held.
#include "curvlab/harness/devices/mapping.hpp"
#include "curvlab/harness/devices/report_parser.hpp"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <span>
#include <string_view>

using namespace curvlab::harness::devices;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto parsed = parse_mapping(text, "fuzz.toml");
  if (!parsed) {
    if (parsed.error().message.rfind("fuzz.toml:", 0) != 0) std::abort();
    return 0;
  }
  const MappingFile& file = parsed.value();
  if (file.devices.empty()) std::abort();
  for (const auto& device : file.devices) {
    if (device.bindings.empty()) std::abort();
    // The input's own bytes as reports of every length up to 65 bytes.
    ReportParser parser(device);
    std::map<int, bool> held;
    std::int64_t t_ns = 0;
    const std::span<const std::uint8_t> bytes(data, size);
    for (std::size_t start = 0, len = 1; start < size; start += len, len = len % 65 + 1) {
      const auto report = bytes.subspan(start, std::min(len, size - start));
      for (const auto& e : parser.parse(report, ++t_ns)) {
        bool& down = held[e.binding_index];
        if ((e.edge == ResponseEvent::Edge::Down) == down) std::abort();  // must alternate
        down = !down;
      }
    }
    for (const auto& e : parser.release_all(++t_ns))
      if (e.edge != ResponseEvent::Edge::Up || !held[e.binding_index]) std::abort();
    if (!parser.release_all(++t_ns).empty()) std::abort();
  }
  return 0;
}
