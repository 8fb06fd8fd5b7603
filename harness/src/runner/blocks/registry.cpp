// The block kinds, registered by name; each kind's file (blocks/<name>.cpp)
// defines its function.
#include "../block_kind.hpp"

#include <array>

namespace curvlab::harness::runner {

const BlockKind& trials_block_kind();
const BlockKind& play_block_kind();
const BlockKind& questionnaire_block_kind();

const BlockKind* find_block_kind(std::string_view name) {
  static const std::array<const BlockKind*, 3> kinds{&trials_block_kind(), &play_block_kind(),
                                                     &questionnaire_block_kind()};
  for (const BlockKind* k : kinds)
    if (k->name() == name) return k;
  return nullptr;
}

Outcome BlockKind::enter(BlockRun& run) const {
  run.frames.event(std::nullopt, data::events::BlockStart{run.block.name, static_cast<std::int64_t>(run.position)});
  return run.frames.pages(run.block.instructions, Phase::instructions, 0, std::nullopt);
}

}  // namespace curvlab::harness::runner
