// Test helper: runs a session that completes trials as fast as it can while
// pushing tracking samples, and prints "committed <trial_index>" after each
// complete_trial() returns. The crash test kills it with SIGKILL at random
// instants and checks that every printed trial is in the file.
#include "curvlab/harness/data/sample_writer.hpp"
#include "curvlab/harness/data/session_store.hpp"

#include <cstdio>
#include <string>

using namespace curvlab::harness::data;

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: data_crash_writer DB\n");
    return 2;
  }
  auto db = Database::open(argv[1], OpenMode::create_or_open);
  if (!db) {
    std::fprintf(stderr, "%s\n", db.error().message.c_str());
    return 1;
  }
  SessionStore store(std::move(db).value());
  const auto protocol = store.add_protocol("crash", "name = \"crash\"\n").value();
  const auto participant = store.add_participant({"P01", 0.063, DominantEye::right}).value();
  SessionRecord rec;
  rec.protocol_id = protocol;
  rec.participant_id = participant;
  rec.software_version = "test";
  rec.software_commit = "test";
  rec.renderer_device = "none";
  rec.renderer_driver = "none";
  const auto session = store.create_session(rec).value();
  BlockPlan block{"main", false, "{}", {}};
  for (int i = 0; i < 2000; ++i)
    block.trials.push_back({"{\"i\":" + std::to_string(i) + "}", "{}"});
  (void)store.store_plan(session, {block}).value();
  auto writer = SampleWriter::open(argv[1]).value();
  std::int64_t t_ns = 0;
  for (;;) {
    auto next = store.next_incomplete_trial(session).value();
    if (!next) break;
    (void)store.begin_trial(next->trial_id).value();
    for (int k = 0; k < 30; ++k) {
      TrackingSample s;
      s.session_id = session;
      s.trial_id = next->trial_id;
      s.t_ns = ++t_ns;
      s.device = static_cast<TrackedDevice>(k % 3);
      writer->push_tracking(s);
    }
    TrialResult r;
    r.trial_id = next->trial_id;
    r.onset_ns = t_ns;
    r.response_ns = t_ns + 1000;
    r.response = "left";
    r.response_device = "keyboard";
    (void)store.complete_trial(r).value();
    std::printf("committed %lld\n", static_cast<long long>(next->trial_index));
    std::fflush(stdout);
  }
  return 0;
}
