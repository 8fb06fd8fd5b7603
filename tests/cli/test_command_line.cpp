// The command line as a person types it: a mistyped command or option gets a
// did-you-mean instead of a message about something else, and `design` and
// `preview` take the participant forms `run` takes.
#include "run_cli.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace {

using curvlab::testing::run_cli;
const std::string kProtocols = std::string(CURVLAB_SOURCE_DIR) + "/protocols/";

TEST(CommandLine, AMistypedCommandGetsADidYouMean) {
  const auto r = run_cli("valdate " + kProtocols + "demo.toml");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("curvlab: error: 'valdate' is not a command of curvlab; did you mean 'validate'?"),
            std::string::npos)
      << r.out;
  // A nested command the same way; a word far from any lists them all.
  const auto nested = run_cli("inspect tabel --space E3 --edge-m 1");
  EXPECT_EQ(nested.exit_code, 2) << nested.out;
  EXPECT_NE(nested.out.find("'tabel' is not a command of curvlab inspect; did you mean 'table'?"), std::string::npos)
      << nested.out;
  const auto far = run_cli("frobnicate");
  EXPECT_EQ(far.exit_code, 2) << far.out;
  EXPECT_NE(far.out.find("Expected one of: "), std::string::npos) << far.out;
  EXPECT_NE(far.out.find("validate"), std::string::npos) << far.out;
}

TEST(CommandLine, AMistypedOptionGetsADidYouMeanBeforeARequiredOptionIsMissed) {
  const auto r = run_cli("run " + kProtocols + "demo.toml --participent P01 --render none");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("curvlab run: unknown option --participent; did you mean --participant?"), std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("--participant is required"), std::string::npos) << r.out;
  const auto eq = run_cli("export --db x.sqlite --formt=csv --out y");
  EXPECT_NE(eq.out.find("unknown option --formt; did you mean --format?"), std::string::npos) << eq.out;
}

// `design` and `preview` read --participant as `run` does: P07 is
// participant number 7, the same trial list as --participant 7.
TEST(CommandLine, DesignTakesThePseudonymsRunTakes) {
  const auto by_name = run_cli("design " + kProtocols + "proposed_study.toml --participant P07 --json");
  ASSERT_EQ(by_name.exit_code, 0) << by_name.out;
  const auto by_number = run_cli("design " + kProtocols + "proposed_study.toml --participant 7 --json");
  ASSERT_EQ(by_number.exit_code, 0) << by_number.out;
  EXPECT_EQ(by_name.out, by_number.out);
  EXPECT_EQ(nlohmann::json::parse(by_name.out)["participant"], 7);
  const auto other = run_cli("design " + kProtocols + "proposed_study.toml --participant P08 --json");
  EXPECT_NE(other.out, by_name.out);
  const auto zero = run_cli("design " + kProtocols + "proposed_study.toml --participant P00");
  EXPECT_EQ(zero.exit_code, 2) << zero.out;
  EXPECT_NE(zero.out.find("--participant P00: its trailing number 00 is 0"), std::string::npos) << zero.out;
}

}  // namespace
