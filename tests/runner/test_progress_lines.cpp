// A session whose stderr goes to a log file (not a terminal) says how far it
// is in plain lines, one per --progress-interval-s: trial k of n, the time
// elapsed and the time left; no carriage returns, no bar.
#include "session_db.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <sys/wait.h>

using curvlab::testing::fresh_dir;

namespace {

const std::string kProtocols = std::string(CURVLAB_SOURCE_DIR) + "/protocols/";

struct Logged {
  int exit_code = -1;
  std::string err;  // what the run wrote to stderr
};

// Runs curvlab with stdout to /dev/null and stderr to a file.
Logged run_logged(const std::string& args, const std::filesystem::path& dir) {
  const auto log = dir / "stderr.log";
  const std::string cmd = std::string(CURVLAB_BIN) + " " + args + " >/dev/null 2>" + log.string();
  const int status = std::system(cmd.c_str());
  Logged out;
  out.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(log, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  out.err = ss.str();
  return out;
}

}  // namespace

TEST(ProgressLines, ALoggedSessionSaysHowFarItIsAtEachInterval) {
  const auto dir = fresh_dir("progress_lines");
  // About 300 trials in a few seconds of wall time: many intervals of 0.2 s.
  const auto r = run_logged("run " + kProtocols + "stick_pse_staircase.toml --participant P01 --db " +
                                (dir / "s.sqlite").string() + " --render none --progress-interval-s 0.2",
                            dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << "a log file gets no carriage returns";
  const std::regex line(R"(curvlab: trial (\d+) of 324 \((practice|main)\), (\d+) s elapsed, )"
                        R"((about (\d+) s left|time left not known yet))");
  std::istringstream lines(r.err);
  std::string text;
  int count = 0, with_estimate = 0;
  long last_trial = 0;
  while (std::getline(lines, text)) {
    std::smatch m;
    ASSERT_TRUE(std::regex_match(text, m, line)) << "not a progress line: " << text;
    const long trial = std::stol(m[1].str());
    EXPECT_GE(trial, last_trial) << text;
    EXPECT_LE(trial, 324) << text;
    last_trial = trial;
    if (m[5].matched) ++with_estimate;
    ++count;
  }
  EXPECT_GE(count, 3) << r.err;
  EXPECT_GE(with_estimate, count - 1) << r.err;
  EXPECT_GT(last_trial, 1);
}

TEST(ProgressLines, QuietAndJsonRunsWriteNone) {
  const auto dir = fresh_dir("progress_quiet");
  for (const char* flag : {"--quiet", "--json"}) {
    SCOPED_TRACE(flag);
    const auto r = run_logged("run " + kProtocols + "demo.toml --participant P01 --db " +
                                  (dir / (std::string(flag + 2) + ".sqlite")).string() +
                                  " --render none --progress-interval-s 0.001 " + flag,
                              dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err.find("curvlab: trial"), std::string::npos) << r.err;
  }
  const auto bad = run_logged("run " + kProtocols + "demo.toml --participant P01 --db " +
                                  (dir / "bad.sqlite").string() + " --progress-interval-s 0",
                              dir);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--progress-interval-s must lie in (0, 86400] seconds"), std::string::npos) << bad.err;
}
