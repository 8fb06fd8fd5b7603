// `curvlab measure stick --from DIR`: the stick's perceived sagitta read
// from a stereo pair (harness/measure/stick.hpp) next to the perception
// model's value. DIR is a `curvlab render` output (left.png, right.png,
// plan.json with its "measure" record) or a `run --images` folder
// (trial_NNNN_left.png, trial_NNNN_right.png, trial_NNNN.json).
#include "common.hpp"

#include "curvlab/harness/measure/stick.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <utility>
#include <variant>

namespace curvlab::harness::cli {
namespace {

namespace fs = std::filesystem;
using harness::measure::StickScene;

struct MeasureArgs {
  std::string from;
  int trial = -1;
  bool json = false;
  std::string observer = "triangulation";
};

struct PairFiles {
  fs::path left, right, record;
  bool plan = false;  // plan.json (the record under "measure") or a trial sidecar
};

std::vector<fs::path> trial_records(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const auto name = entry.path().filename().string();
    if (name.rfind("trial_", 0) == 0 && entry.path().extension() == ".json") out.push_back(entry.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

PairFiles pair_files(const MeasureArgs& a) {
  const fs::path dir(a.from);
  if (!fs::is_directory(dir)) throw UsageError("--from " + a.from + ": no such directory");
  if (fs::exists(dir / "plan.json") && a.trial < 0)
    return {dir / "left.png", dir / "right.png", dir / "plan.json", true};
  if (a.trial >= 0) {
    char stem[32];
    std::snprintf(stem, sizeof stem, "trial_%04d", a.trial);
    return {dir / (std::string(stem) + "_left.png"), dir / (std::string(stem) + "_right.png"),
            dir / (std::string(stem) + ".json"), false};
  }
  const auto records = trial_records(dir);
  if (records.empty())
    throw UsageError("--from " + a.from + ": no plan.json (curvlab render) and no trial_NNNN.json "
                     "(curvlab run --images): nothing records the eye geometry");
  if (records.size() > 1)
    throw UsageError("--from " + a.from + " holds " + std::to_string(records.size()) +
                     " onset pairs; choose one with --trial N");
  const std::string stem = records.front().stem().string();
  return {dir / (stem + "_left.png"), dir / (stem + "_right.png"), records.front(), false};
}

StickScene read_scene(const PairFiles& files) {
  std::ifstream in(files.record);
  if (!in) throw UsageError(files.record.string() + ": cannot read (it records the eye geometry)");
  std::stringstream text;
  text << in.rdbuf();
  auto j = nlohmann::json::parse(text.str(), nullptr, false);
  if (j.is_discarded()) throw UsageError(files.record.string() + ": not valid JSON");
  if (files.plan) {
    if (!j.contains("measure"))
      throw UsageError(files.record.string() + ": no \"measure\" record (written by curvlab render "
                       "--scene stick of this version)");
    j = j["measure"];
  }
  auto scene = harness::measure::parse_scene_json(j);
  if (!scene) throw UsageError(files.record.string() + ": " + scene.error().message);
  return scene.value();
}

// An image named on the command line that is missing or does not decode is
// the command's to fix (exit 2), whatever the renderer's kind says.
renderer::Rgba8Image read_image(const fs::path& path) {
  if (!fs::exists(path)) throw UsageError(path.string() + ": no such image");
  auto read = renderer::read_png(path.string());
  if (auto* e = std::get_if<renderer::RenderError>(&read)) throw UsageError(e->message);
  return std::get<renderer::Rgba8Image>(std::move(read));
}

void print_text(const harness::measure::StickEstimate& e) {
  std::printf("estimated_sagitta_m: %.6f\nmodel_sagitta_m: %.6f\ndifference_m: %.6f\n"
              "estimated_bend_m: %.6f\nmodel_bend_m: %.6f\nbinocular: %s\nfit_rms_m: %.6f\n",
              e.estimated_sagitta_m, e.model_sagitta_m, e.estimated_sagitta_m - e.model_sagitta_m,
              e.estimated_bend_m, e.model_bend_m, e.binocular ? "true" : "false", e.fit_rms_m);
  if (e.features.empty()) return;
  std::printf("%-11s %8s %19s %19s %28s %9s %9s\n", "feature", "u_m", "left_px", "right_px", "position_m",
              "res_l_px", "res_r_px");
  for (const auto& f : e.features)
    std::printf("%-11s %8.3f %9.3f,%9.3f %9.3f,%9.3f %9.4f,%9.4f,%9.4f %9.4f %9.4f\n", f.name.c_str(), f.u_m,
                f.left_px.x, f.left_px.y, f.right_px.x, f.right_px.y, f.position_m.x, f.position_m.y,
                f.position_m.z, f.residual_left_px, f.residual_right_px);
}

void run_measure_stick(const MeasureArgs& a) {
  const PairFiles files = pair_files(a);
  const StickScene scene = read_scene(files);
  const auto left = read_image(files.left);
  const auto right = read_image(files.right);
  if (a.observer != "triangulation" && a.observer != "human")
    throw UsageError("--observer must be triangulation or human, got '" + a.observer + "'");
  const geometry::HumanVision vision;  // the human model's default limits (docs/runner.md)
  const auto estimate =
      harness::measure::measure_stick(left, right, scene, a.observer == "human" ? &vision : nullptr);
  if (!estimate) raise(estimate.error());
  if (a.json) {
    Json j = harness::measure::estimate_json(estimate.value());
    j["record"] = files.record.string();
    std::cout << j.dump(2) << '\n';
  } else {
    print_text(estimate.value());
  }
}

}  // namespace

void add_measure_commands(CLI::App& app) {
  auto* measure = app.add_subcommand("measure", "read stimulus properties from rendered images");
  measure->require_subcommand(1);
  auto args = std::make_shared<MeasureArgs>();
  auto* stick = measure->add_subcommand(
      "stick", "the cue stick's perceived sagitta from a stereo pair, next to the perception model's value");
  stick->add_option("--from", args->from, "a curvlab render output or a run --images folder")->required();
  stick->add_option("--trial", args->trial, "the onset pair trial_NNNN of a run --images folder");
  stick->add_flag("--json", args->json, "one JSON object");
  stick->add_option("--observer", args->observer,
                    "triangulation (default: the lines of sight met exactly) or human (the simulated participant's "
                    "default limits, as run --observer image reads the pair)");
  stick->callback([args] { run_measure_stick(*args); });
}

}  // namespace curvlab::harness::cli
