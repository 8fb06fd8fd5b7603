// Warnings before participant hours, as an author meets them: `validate`
// names the eye and condition whose stimulus leaves the view, `predict`
// says where the human observer model is outside its range of validity,
// and a staircase that cannot converge inside its range is flagged; a
// protocol with none of these gets no warning.
#include "run_cli.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <unistd.h>

namespace {

using curvlab::testing::run_cli;
const std::string kProtocols = std::string(CURVLAB_SOURCE_DIR) + "/protocols/";

int count_of(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(Warnings, ValidateNamesTheEyeAndConditionWhoseStickLeavesTheView) {
  // one_eye_vs_two.toml: in S3 the metre-long stick's ends lie 46° to the
  // side, outside a headset's 90° field of view; with one eye shown, only
  // that eye's loss is named.
  const auto r = run_cli("validate " + kProtocols + "one_eye_vs_two.toml");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("warning: block s3, condition eyes=left space=S3: the stimulus leaves the view: the left eye "
                       "loses the stick's right end (46° across, 0° vertically) — outside a headset's default "
                       "90°×90° field of view"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("warning: block s3, condition eyes=right space=S3: the stimulus leaves the view: the right "
                       "eye loses the stick's left end"),
            std::string::npos)
      << r.out;
  // E3 and H3 keep the stick in view.
  EXPECT_EQ(r.out.find("condition eyes=both space=E3: the stimulus leaves"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("space=H3: the stimulus leaves"), std::string::npos) << r.out;

  const auto j = run_cli("validate --json " + kProtocols + "one_eye_vs_two.toml");
  ASSERT_EQ(j.exit_code, 0) << j.out;
  const auto doc = nlohmann::json::parse(j.out);
  int out_of_view = 0;
  for (const auto& w : doc["warnings"])
    if (w["kind"] == "out_of_view") {
      ++out_of_view;
      EXPECT_EQ(w["block"], "s3");
    }
  EXPECT_EQ(out_of_view, 3) << doc["warnings"].dump(2);
}

TEST(Warnings, PredictOnTheStickPseStaircaseWarnsAboutTheModelsRange) {
  const auto r = run_cli("predict " + kProtocols + "stick_pse_staircase.toml --simulations 20");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("warning: block main: in 4 of its 4 binocular conditions the human observer model's "
                       "predictions lie outside its range of validity"),
            std::string::npos)
      << r.out;
  // The same from validate, before anyone predicts.
  const auto v = run_cli("validate " + kProtocols + "stick_pse_staircase.toml");
  EXPECT_NE(v.out.find("the human observer model's predictions lie outside its range of validity"),
            std::string::npos)
      << v.out;
}

TEST(Warnings, TheDemoHasNone) {
  const auto r = run_cli("validate " + kProtocols + "demo.toml");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(count_of(r.out, "warning:"), 0) << r.out;
}

// Narrowed to [0.05, 0.15] m, the stick PSE staircases' range misses where
// the mean observer answers convex half the time: validate says so.
TEST(Warnings, AStaircaseThatCannotConvergeInsideItsRangeIsFlagged) {
  std::ifstream in(kProtocols + "stick_pse_staircase.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string narrowed = std::regex_replace(text.str(), std::regex("\nmin = -0\\.15\n"), "\nmin = 0.05\n");
  narrowed = std::regex_replace(narrowed, std::regex("\nstart = -0\\.06\n"), "\nstart = 0.1\n");
  ASSERT_NE(narrowed, text.str());
  const auto dir = std::filesystem::temp_directory_path() / ("curvlab_warnings_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto file = dir / "narrow.toml";
  std::ofstream(file) << narrowed;
  const auto r = run_cli("validate " + file.string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("cannot converge inside its range [0.05, 0.15] of stimulus.stick_sagitta_m"),
            std::string::npos)
      << r.out;
  std::filesystem::remove_all(dir);
}

}  // namespace
