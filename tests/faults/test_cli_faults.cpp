// The real `curvlab` program meeting a fault part-way through a session: a
// lost Vulkan device in a headless run (the test Vulkan layer, enabled
// through the loader's environment) and a lost OpenXR session or failing
// runtime in a headset run (the test runtime's CURVLAB_TEST_XR_FAIL). The
// program has no switch for either. Each run must exit 1 with a message
// naming the API call and its result, leave the session `interrupted` with
// its completed trials, and `curvlab resume` must complete it.
#include "fault_env.hpp"

#include "../cli/run_cli.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <unistd.h>
#include <vector>

namespace {

using curvlab::testing::run_cli;
using curvlab::testing::VulkanFault;
namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("curvlab_faults_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string scalar(const fs::path& db_path, const std::string& sql) {
  sqlite3* db = nullptr;
  std::string out = "(no database)";
  if (sqlite3_open_v2(db_path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* stmt = nullptr;
    out = "(no row)";
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt, nullptr) == SQLITE_OK && sqlite3_step(stmt) == SQLITE_ROW) {
      const auto* text = sqlite3_column_text(stmt, 0);
      out = text == nullptr ? "NULL" : reinterpret_cast<const char*>(text);
    }
    sqlite3_finalize(stmt);
  }
  sqlite3_close(db);
  return out;
}

int completed(const fs::path& db) {
  return std::stoi(scalar(db, "SELECT count(*) FROM trials WHERE status = 'completed'"));
}

// The OpenXR test runtime's environment for one run.
class XrRuntime {
 public:
  explicit XrRuntime(const std::map<std::string, std::string>& vars) {
    setenv("XR_RUNTIME_JSON", CURVLAB_TEST_XR_RUNTIME_JSON, 1);
    for (const auto& [k, v] : vars) {
      setenv(k.c_str(), v.c_str(), 1);
      names_.push_back(k);
    }
  }
  ~XrRuntime() {
    unsetenv("XR_RUNTIME_JSON");
    for (const auto& k : names_) unsetenv(k.c_str());
  }
  XrRuntime(const XrRuntime&) = delete;
  XrRuntime& operator=(const XrRuntime&) = delete;

 private:
  std::vector<std::string> names_;
};

// A, X and the right trigger in turn, one answer every 0.6 s from 1 s after
// focus (tests/xr/test_xr_session.cpp explains the rhythm).
const std::string kPresses = "right:a@1.0/1.8,left:x@1.6/1.8,right:trigger@2.2/1.8";
const std::string kXrProtocol = std::string(CURVLAB_SOURCE_DIR) + "/tests/xr/demo_buttons.toml";
const std::string kDemo = std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml";

// What a fault must leave behind, and the resume that completes it.
void expect_interrupted(const curvlab::testing::CliResult& r, const fs::path& db, const std::string& api_result) {
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find(api_result), std::string::npos) << r.out;
  EXPECT_EQ(scalar(db, "SELECT status FROM sessions"), "interrupted") << r.out;
  const int done = completed(db);
  EXPECT_GT(done, 0) << r.out;
  EXPECT_LT(done, 8) << r.out;
  std::cout << "exit " << r.exit_code << "; kept " << done << " of 8 trials; output:\n" << r.out;
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM trials WHERE status = 'completed' AND response IS NULL"), "0");
}

// The runtime's log after a fault: the fault happened, curvlab broke no
// rule while tearing down, and the instance was destroyed.
void expect_clean_teardown(const fs::path& log_path, const std::string& fault) {
  std::ifstream in(log_path);
  std::string line;
  bool faulted = false;
  bool destroyed = false;
  while (std::getline(in, line)) {
    EXPECT_NE(line.rfind("violation", 0), 0u) << line;
    EXPECT_NE(line.rfind("warning", 0), 0u) << line;
    faulted = faulted || line == "fault " + fault;
    destroyed = destroyed || line == "instance destroyed";
  }
  EXPECT_TRUE(faulted) << "no 'fault " << fault << "' line in " << log_path;
  EXPECT_TRUE(destroyed) << "the OpenXR instance was not destroyed";
}

}  // namespace

TEST(CliFaults, HeadlessDeviceLossExitsOneNamingItAndResumes) {
  const auto dir = fresh_dir("headless");
  const auto db = dir / "demo.sqlite";
  std::string done_before;
  {
    // Onset frames only: each trial draws once, so the 5th submission
    // (text panels upload too) falls a few trials in.
    const VulkanFault fault("vkQueueSubmit@5");
    const auto r = run_cli("run " + kDemo + " --participant F01 --db " + db.string() +
                           " --software --render onset --quiet");
    expect_interrupted(r, db, "vkQueueSubmit: VK_ERROR_DEVICE_LOST");
    EXPECT_NE(r.out.find("curvlab test vulkan layer: vkQueueSubmit #5 returns VK_ERROR_DEVICE_LOST"),
              std::string::npos)
        << r.out;
    done_before = scalar(db, "SELECT group_concat(trial_index || ':' || response || ':' || rt_ns) FROM "
                             "(SELECT * FROM trials WHERE status = 'completed' ORDER BY trial_index)");
  }
  const auto r = run_cli("resume --db " + db.string() + " --session 1 --software --render onset --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(scalar(db, "SELECT status FROM sessions"), "completed");
  EXPECT_EQ(completed(db), 8);
  // The trials completed before the fault are the same rows, untouched.
  const std::string kept = scalar(db, "SELECT group_concat(trial_index || ':' || response || ':' || rt_ns) FROM "
                                      "(SELECT * FROM trials WHERE status = 'completed' ORDER BY trial_index)");
  EXPECT_EQ(kept.rfind(done_before, 0), 0u) << kept << " vs " << done_before;
  fs::remove_all(dir);
}

namespace {

// A headset run that meets `fault` (CURVLAB_TEST_XR_FAIL) ends interrupted
// with `named` in its message, tears down cleanly, and resumes to the end.
void xr_fault_then_resume(const std::string& name, const std::string& participant, const std::string& fault,
                          const std::string& named) {
  const auto dir = fresh_dir(name);
  const auto db = dir / "xr.db";
  {
    XrRuntime env({{"CURVLAB_TEST_XR_PRESS", kPresses},
                   {"CURVLAB_TEST_XR_FAIL", fault},
                   {"CURVLAB_TEST_XR_LOG", (dir / "runtime.log").string()}});
    const auto r =
        run_cli("run " + kXrProtocol + " --participant " + participant + " --backend xr --db " + db.string() + " --quiet");
    expect_interrupted(r, db, named);
  }
  std::string logged = named;
  logged.replace(logged.find(": "), 2, " ");
  expect_clean_teardown(dir / "runtime.log", logged);
  XrRuntime env({{"CURVLAB_TEST_XR_PRESS", kPresses}});
  const auto r = run_cli("resume --db " + db.string() + " --session 1 --backend xr --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(scalar(db, "SELECT status FROM sessions"), "completed");
  EXPECT_EQ(completed(db), 8);
  fs::remove_all(dir);
}

}  // namespace

TEST(CliFaults, XrSessionLostInWaitFrameExitsOneNamingItAndResumes) {
  xr_fault_then_resume("xr_wait", "X05", "xrWaitFrame@2.5:XR_ERROR_SESSION_LOST", "xrWaitFrame: XR_ERROR_SESSION_LOST");
}

TEST(CliFaults, XrRuntimeFailureInEndFrameExitsOneNamingItAndResumes) {
  xr_fault_then_resume("xr_end", "X06", "xrEndFrame@2.5:XR_ERROR_RUNTIME_FAILURE",
                       "xrEndFrame: XR_ERROR_RUNTIME_FAILURE");
}
