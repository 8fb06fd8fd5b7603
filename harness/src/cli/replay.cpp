// `curvlab replay`: one frame of a stored trial re-rendered from the logged
// poses.
#include "common.hpp"

#include "curvlab/harness/runner/replay.hpp"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <memory>
#include <optional>

namespace curvlab::harness::cli {
namespace {

namespace rn = curvlab::harness::runner;

struct ReplayArgs {
  rn::ReplayRequest request;
  std::optional<std::int64_t> frame;
  bool json = false;
};

void replay_command(ReplayArgs a) {
  a.request.frame_index = a.frame;
  check_db_argument(a.request.db_path);
  auto r = rn::replay_frame(a.request);
  if (!r) {
    if (curvlab::harness::exit_code(r.error()) == 2) throw UsageError(r.error().message);
    throw RuntimeFailure(r.error().message);
  }
  const auto& res = r.value();
  Json doc;
  doc["frame_index"] = res.frame_index;
  doc["phase"] = res.phase;
  doc["device"] = res.device;
  doc["files"] = res.files;
  print_result(doc, a.json);
}

}  // namespace

void add_replay_command(CLI::App& app) {
  auto ra = std::make_shared<ReplayArgs>();
  auto* rp = app.add_subcommand("replay", "re-render one frame of a stored trial from the logged poses");
  rp->add_option("--db", ra->request.db_path, "SQLite file")->required();
  rp->add_option("--session", ra->request.session_id, "session id")->required();
  rp->add_option("--trial", ra->request.trial_index, "trial index in the session (from 0)")->required();
  rp->add_option_function<std::int64_t>("--frame", [ra](std::int64_t f) { ra->frame = f; },
                                        "frame index (default: the stimulus onset)");
  rp->add_option("--out", ra->request.out_dir, "output folder")->required();
  rp->add_flag("--software", ra->request.software, "use lavapipe even with a GPU");
  rp->add_flag("--json", ra->json, "print JSON");
  rp->callback([ra] { replay_command(*ra); });
}

}  // namespace curvlab::harness::cli
