// Reading a protocol file: TOML text → Protocol, or every problem found.
// Never throws for bad input, never writes anything. Thread-safe (no shared
// state).
#pragma once

#include "curvlab/harness/protocol/diagnostic.hpp"
#include "curvlab/harness/protocol/protocol.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::protocol {

struct LoadResult {
  std::optional<Protocol> protocol;  // set only when diagnostics is empty
  std::vector<Diagnostic> diagnostics;
  std::string text;  // load_protocol_file: the text read (sessions store it)
  [[nodiscard]] bool ok() const { return protocol.has_value(); }
};

// `file` names the text in diagnostics.
LoadResult load_protocol_text(std::string_view text, const std::string& file);
LoadResult load_protocol_file(const std::string& path);

// The names the loader accepts in `keys` and `buttons` arrays (the JSON
// Schema lists the same).
const std::vector<std::string>& response_key_names();
const std::vector<std::string>& response_button_names();

}  // namespace curvlab::harness::protocol
