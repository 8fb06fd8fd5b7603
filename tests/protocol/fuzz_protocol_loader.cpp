// libFuzzer entry point for the protocol loader (built only with
// -DCURVLAB_FUZZ=ON and clang; run by bench/fuzz_protocol.sh). Any input must
// give either a protocol or diagnostics — never a crash, hang or sanitizer
// report — and an accepted protocol must expand.
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/loader.hpp"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

using namespace curvlab::harness::protocol;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const auto r = load_protocol_text(text, "fuzz.toml");
  if (!r) {
    if (r.error().diagnostics.empty()) std::abort();  // a failure says where
    for (const auto& d : r.error().diagnostics) {
      if (format_diagnostic(d).empty()) std::abort();
    }
    return 0;
  }
  // Expand small designs only: a valid protocol may hold up to 10^6 trials,
  // which is correct but would slow the search to a crawl.
  std::size_t trials = 0;
  for (const auto& b : r->blocks) {
    trials += b.judgement.type->trials_per_cell(b) * block_cells(*r, b).size();
    if (trials > 5000) return 0;
  }
  const Design d = expand_design(*r, 1 + size % 7);
  if (d.trials.size() != trials) std::abort();
  return 0;
}
