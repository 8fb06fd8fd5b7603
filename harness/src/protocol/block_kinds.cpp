// The block kinds a protocol may name (`kind` of a [[blocks]] table), in the
// order users see them. What each kind's frames show is the runner's
// (harness/src/runner/blocks/); a kind with keys of its own reads them here.
#include "curvlab/harness/protocol/protocol.hpp"

namespace curvlab::harness::protocol {

const std::vector<std::string>& block_kind_names() {
  static const std::vector<std::string> names{"trials", "play", "questionnaire"};
  return names;
}

}  // namespace curvlab::harness::protocol
