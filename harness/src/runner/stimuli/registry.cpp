// The stimulus kinds, registered in the order a trial's judged kind is
// chosen and its objects are built. Each kind's file (stimuli/<name>.cpp)
// defines its function; a new kind declares it here.
#include "curvlab/harness/runner/stimulus_kind.hpp"

namespace curvlab::harness::runner {

const std::vector<const StimulusKind*>& stimulus_kinds() {
  static const std::vector<const StimulusKind*> kinds{
      &stick_stimulus_kind(),
      &table_stimulus_kind(),
  };
  return kinds;
}

std::size_t judged_index(const protocol::Settings& s) {
  const auto& kinds = stimulus_kinds();
  for (std::size_t i = 0; i < kinds.size(); ++i)
    if (kinds[i]->shown(s)) return i;
  for (std::size_t i = 0; i < kinds.size(); ++i)
    if (kinds[i] == &table_stimulus_kind()) return i;
  return 0;
}

const StimulusKind& judged_kind(const protocol::Settings& s) { return *stimulus_kinds()[judged_index(s)]; }

}  // namespace curvlab::harness::runner
