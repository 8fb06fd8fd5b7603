#include "curvlab/harness/runner/calibration.hpp"

#include "curvlab/geometry/table.hpp"
#include "curvlab/geometry/tracking.hpp"
#include "curvlab/harness/render_result.hpp"
#include "curvlab/harness/runner/view_record.hpp"
#include "curvlab/renderer/colour.hpp"
#include "curvlab/renderer/plan.hpp"
#include "curvlab/renderer/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <numbers>
#include <sstream>

namespace curvlab::harness::runner {

using geometry::Isometry;
using geometry::Vec3;

namespace {

constexpr std::array<const char*, 4> kCornerNames = {"front-left", "front-right", "back-right", "back-left"};

std::string mm(double metres) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", metres * 1000.0);
  return text;
}

// "pull the trigger (or press space)": the way of each control at hand.
std::string either(const CalibrationControls& c, const std::string& controller, const std::string& keyboard) {
  const bool both = c.controller == c.keyboard;  // neither known: name both
  if (both) return controller + " (or " + keyboard + ")";
  return c.controller ? controller : keyboard;
}

// Greedy word wrap at `columns`, keeping the text's own line breaks: the
// panel shrinks its font to the longest line, so long lines would be small.
std::string wrap(const std::string& text, std::size_t columns) {
  std::string out;
  std::istringstream lines(text);
  std::string line;
  bool first_line = true;
  while (std::getline(lines, line)) {
    if (!first_line) out += '\n';
    first_line = false;
    std::istringstream words(line);
    std::string word;
    std::size_t used = 0;
    while (words >> word) {
      if (used > 0 && used + 1 + word.size() > columns) {
        out += '\n';
        used = 0;
      } else if (used > 0) {
        out += ' ';
        ++used;
      }
      out += word;
      used += word.size();
    }
  }
  return out;
}

std::string touching_text(const CalibrationSteps& s, const CalibrationControls& c) {
  const int k = s.next_corner();
  std::string text = "Touch the " + std::string(kCornerNames[static_cast<std::size_t>(k)]) + " corner " +
                     either(c, "with the right controller and pull the trigger",
                            "with the right hand and press space") +
                     ".\n";
  if (k == 3) text += "Or fit the three corners touched: " + either(c, "press B", "press F") + ".\n";
  text += "Corners touched: " + std::to_string(k) + " of 4.";
  if (!s.note().empty()) text += "\n" + s.note();
  return text;
}

std::string fit_lines(const geometry::PhysicalTableFit& fit) {
  std::string residuals;
  for (int j = 0; j < fit.corners_used; ++j)
    residuals += (j > 0 ? ", " : "") + mm(fit.corner_residual_m[static_cast<std::size_t>(j)]);
  char yaw[32];
  std::snprintf(yaw, sizeof yaw, "%.1f", fit.yaw_rad * 180.0 / std::numbers::pi);
  return "Edge " + mm(fit.edge_m) + " mm, height " + mm(fit.height_m) + " mm, turned " + yaw +
         " degrees.\nResiduals " + residuals + " mm (RMS " + mm(fit.rms_residual_m) + " mm).";
}

// Display colours (renderer/colour.hpp): the corner to touch, the tip,
// touches so far, touches a fit keeps, touches refused.
const glm::vec4 kMarker = renderer::display(1.0f, 0.85f, 0.1f);
const glm::vec4 kTip = renderer::display(0.95f, 0.95f, 0.95f);
const glm::vec4 kTouched = renderer::display(0.35f, 0.65f, 1.0f);
const glm::vec4 kWithin = renderer::display(0.2f, 0.85f, 0.3f);
const glm::vec4 kRefused = renderer::display(0.9f, 0.1f, 0.1f);

Isometry at(const geometry::Space& space, const Vec3& p_m) { return geometry::translation_m(space, p_m); }

// Model → lab of a table: the cloth's plane at the table's height, turned by its yaw.
Isometry table_pose(const geometry::Space& space, const geometry::PhysicalTableFit& t) {
  return at(space, Vec3(t.centre_m.x, t.height_m, t.centre_m.y)) *
         geometry::rotation(Vec3(0.0, 1.0, 0.0), t.yaw_rad);
}

// A thin slab the size of the touched table top: no cushions or rails
// beyond the corners the participant touches.
renderer::TableStyle slab_style() {
  renderer::TableStyle style;
  style.cushion_width_m = 0.004;
  style.cushion_height_m = 0.004;
  style.rail_width_m = 0.004;
  style.skirt_depth_m = 0.05;
  return style;
}

std::variant<geometry::TableShape, geometry::GeometryError> square(double edge_m) {
  return geometry::right_angled_table_from_edge(geometry::SpaceKind::E3, edge_m, 4);
}

}  // namespace

std::string_view to_string(CalibrationStage stage) {
  switch (stage) {
    case CalibrationStage::touching: return "touching";
    case CalibrationStage::fitted: return "fitted";
    case CalibrationStage::refused: return "refused";
    case CalibrationStage::accepted: return "accepted";
  }
  return "unknown";
}

std::optional<CalibrationCommand> calibration_command(const io::InputEvent& in, CalibrationStage stage) {
  if (!in.pressed) return std::nullopt;
  const auto means = [&](io::Intent i) { return in.intents.has(i); };
  switch (stage) {
    case CalibrationStage::touching:
      if (means(io::Intent::calibration_touch)) return CalibrationCommand::touch;
      if (means(io::Intent::calibration_fit_three)) return CalibrationCommand::fit_three;
      return std::nullopt;
    case CalibrationStage::fitted:
      if (means(io::Intent::calibration_accept)) return CalibrationCommand::accept;
      if (means(io::Intent::calibration_redo)) return CalibrationCommand::redo;
      return std::nullopt;
    case CalibrationStage::refused:
      if (means(io::Intent::calibration_touch) || means(io::Intent::calibration_redo)) return CalibrationCommand::redo;
      return std::nullopt;
    case CalibrationStage::accepted: return std::nullopt;
  }
  return std::nullopt;
}

CalibrationControls calibration_controls(const std::vector<io::Reach>& sources) {
  CalibrationControls c;
  for (const auto& r : sources) {
    if (r.simulated || !r.intents.has(io::Intent::calibration_touch)) continue;
    c.controller = c.controller || r.kind == io::SourceKind::xr_controller;
    c.keyboard = c.keyboard || r.kind == io::SourceKind::keyboard || r.kind == io::SourceKind::script;
  }
  return c;
}

bool CalibrationSteps::apply(CalibrationCommand command, const std::optional<Vec3>& tip_m) {
  switch (stage_) {
    case CalibrationStage::touching:
      if (command == CalibrationCommand::touch) {
        if (!tip_m) {
          note_ = "The right controller was not tracked: touch the corner again.";
          return true;
        }
        note_.clear();
        touches_.push_back(*tip_m);
        if (touches_.size() == 4) fit_touches();
        return true;
      }
      if (command == CalibrationCommand::fit_three && touches_.size() == 3) {
        fit_touches();
        return true;
      }
      return false;
    case CalibrationStage::fitted:
      if (command == CalibrationCommand::accept) {
        stage_ = CalibrationStage::accepted;
        return true;
      }
      if (command != CalibrationCommand::redo) return false;
      start_again();
      return true;
    case CalibrationStage::refused:
      if (command != CalibrationCommand::redo) return false;
      start_again();
      return true;
    case CalibrationStage::accepted: return false;
  }
  return false;
}

void CalibrationSteps::fit_touches() {
  note_.clear();
  auto fitted = geometry::fit_square_table(touches_, limits_);
  if (auto* fit = std::get_if<geometry::PhysicalTableFit>(&fitted)) {
    fit_ = *fit;
    stage_ = CalibrationStage::fitted;
    return;
  }
  refusal_ = std::get<geometry::GeometryError>(fitted).message;
  refusals_.push_back(refusal_);
  fit_.reset();
  stage_ = CalibrationStage::refused;
}

void CalibrationSteps::start_again() {
  touches_.clear();
  fit_.reset();
  refusal_.clear();
  note_.clear();
  ++redone_;
  stage_ = CalibrationStage::touching;
}

std::string calibration_text(const CalibrationSteps& s, const CalibrationControls& c) {
  std::string text;
  switch (s.stage()) {
    case CalibrationStage::touching: text = touching_text(s, c); break;
    case CalibrationStage::fitted:
      text = "The table fitted to " + std::to_string(s.fit()->corners_used) + " corners:\n" + fit_lines(*s.fit()) +
             "\nKeep it: " + either(c, "press A", "press Enter") + ". Touch the corners again: " +
             either(c, "press B", "press R") + ".";
      break;
    case CalibrationStage::refused:
      text = "These touches were refused: " + s.refusal() + ".\nTouch the corners again: " +
             either(c, "pull the trigger or press B", "press space or R") + ".";
      break;
    case CalibrationStage::accepted: text = "Table calibrated.\n" + fit_lines(*s.fit()); break;
  }
  return wrap(text, 48);
}

namespace {

// What the participant sees: the table (as known, then as fitted), a marker
// on the corner to touch, the touches so far, the controller's tip and the
// text panel, in the lab's own (flat) coordinates. Not thread-safe.
class CalibrationScene {
 public:
  static Result<CalibrationScene> build(const CalibrationOptions& o) {
    CalibrationScene c;
    c.font_ = o.font_path.empty() ? std::string(CURVLAB_DEFAULT_FONT) : o.font_path;
    c.known_ = o.known;
    auto shape = square(o.known.edge_m);
    if (auto* e = std::get_if<geometry::GeometryError>(&shape))
      return Error{Error::Kind::bad_input, "the table as known cannot be drawn: " + e->message};
    c.table_ = c.scene_.add(renderer::table_object(c.space_, std::get<geometry::TableShape>(shape), slab_style()));
    c.table_edge_m_ = o.known.edge_m;
    c.scene_.edit(c.table_).pose = table_pose(c.space_, o.known);
    c.marker_ = c.scene_.add(renderer::ball_object(c.space_, 0.025, kMarker, Isometry::identity()));
    c.tip_ = c.scene_.add(renderer::ball_object(c.space_, 0.008, kTip, Isometry::identity()));
    for (auto& t : c.touched_)
      t = c.scene_.add(renderer::ball_object(c.space_, 0.015, {1.0f, 1.0f, 1.0f, 1.0f}, Isometry::identity()));
    auto panel = from_renderer(
        renderer::text_panel_object(c.space_, "calibration", " ", c.font_, 1.0, 0.5, Isometry::identity()));
    if (!panel) return panel.error();
    c.panel_ = c.scene_.add(std::move(panel).value());
    c.scene_.edit(c.panel_).visible = false;
    return c;
  }

  // Places the markers for the steps and the tip this frame.
  void show(const CalibrationSteps& s, const std::optional<Vec3>& tip_m) {
    const bool touching = s.stage() == CalibrationStage::touching;
    const geometry::PhysicalTableFit& table = s.fit() ? *s.fit() : known_;
    set_table(table);
    set(marker_, touching, touching ? geometry::physical_table_corner(known_, s.next_corner()) : Vec3(0.0));
    set(tip_, tip_m.has_value() && s.stage() != CalibrationStage::accepted, tip_m.value_or(Vec3(0.0)));
    for (std::size_t j = 0; j < touched_.size(); ++j) {
      const bool shown = j < s.touches().size();
      set(touched_[j], shown, shown ? s.touches()[j] : Vec3(0.0));
      if (shown) tint(touched_[j], touch_colour(s, static_cast<int>(j)));
    }
  }

  // The panel's text; placed in front of the head (turned with it about the
  // vertical only, a little below the eyes) whenever the text changes.
  Result<Done> set_text(const std::string& text, const geometry::LabPose& head) {
    if (text == text_ && placed_) return Done{};
    if (text != text_) {
      auto made = from_renderer(renderer::text_panel_object(space_, "calibration", text, font_, 1.0, 0.5,
                                                            Isometry::identity()));
      if (!made) return made.error();
      auto& o = made.value();
      scene_.replace_mesh(panel_, std::move(o.build), std::move(o.info), std::move(o.text));
      text_ = text;
    }
    if (geometry::usable(head)) {
      const Vec3 forward = head.orientation * Vec3(0.0, 0.0, -1.0);
      const double yaw = std::atan2(-forward.x, -forward.z);
      const Isometry turn = geometry::rotation(Vec3(0.0, 1.0, 0.0), yaw);
      scene_.edit(panel_).pose = at(space_, head.position_m) * turn * at(space_, Vec3(0.0, -0.3, -1.2));
      scene_.edit(panel_).visible = true;
      placed_ = true;
    }
    return Done{};
  }

  renderer::Scene& scene() { return scene_; }
  [[nodiscard]] const geometry::Space& space() const { return space_; }

 private:
  void set(std::size_t i, bool visible, const Vec3& p_m) {
    const Isometry pose = at(space_, p_m);
    const auto& o = scene_.objects()[i];
    if (o.visible != visible) scene_.edit(i).visible = visible;
    if (visible && o.pose.m != pose.m) scene_.edit(i).pose = pose;
  }
  void tint(std::size_t i, const glm::vec4& colour) {
    if (scene_.objects()[i].tint != colour) scene_.edit(i).tint = colour;
  }
  // Touches light blue; after a fit, green within the limit and red beyond.
  static glm::vec4 touch_colour(const CalibrationSteps& s, int j) {
    if (s.stage() == CalibrationStage::refused) return kRefused;
    if (!s.fit()) return kTouched;
    const bool within = s.fit()->corner_residual_m[static_cast<std::size_t>(j)] <= s.limits().max_residual_m;
    return within ? kWithin : kRefused;
  }
  void set_table(const geometry::PhysicalTableFit& t) {
    if (t.edge_m != table_edge_m_) {
      if (auto shape = square(t.edge_m); std::holds_alternative<geometry::TableShape>(shape)) {
        auto o = renderer::table_object(space_, std::get<geometry::TableShape>(shape), slab_style());
        scene_.replace_mesh(table_, std::move(o.build), std::move(o.info));
        table_edge_m_ = t.edge_m;
      }
    }
    const Isometry pose = table_pose(space_, t);
    if (scene_.objects()[table_].pose.m != pose.m) scene_.edit(table_).pose = pose;
  }

  geometry::Space space_{geometry::SpaceKind::E3, 1.0};
  renderer::Scene scene_;
  geometry::PhysicalTableFit known_;
  std::size_t table_ = 0, marker_ = 0, tip_ = 0, panel_ = 0;
  std::array<std::size_t, 4> touched_{};
  double table_edge_m_ = 0.0;
  std::string font_, text_;
  bool placed_ = false;
};

// The frame loop: poses → inputs → steps → scene → submit, until a fit is
// accepted or the devices end it.
class CalibrationRun {
 public:
  CalibrationRun(const io::Station& station, const CalibrationOptions& options, CalibrationScene scene)
      : station_(station), options_(options), steps_(options.limits), scene_(std::move(scene)) {
    std::vector<io::Reach> reach;
    for (const io::ResponseSource* source : station_.responses) reach.push_back(source->reach());
    controls_ = calibration_controls(reach);
    eye_size_ = eye_image_size(station_.display->info(), options_.width_px, options_.height_px);
  }

  Result<CalibrationResult> run() {
    std::vector<io::InputEvent> inputs;
    for (bool first = true;; first = false) {
      if (stopped()) return ended();
      const auto timing = station_.display->begin_frame();
      if (!timing) return ended();
      const geometry::LabFrame lab = station_.poses->poses(*timing);
      inputs.clear();
      if (poll(inputs) == io::Signal::quit) return ended();
      const std::optional<Vec3> tip = tip_of(lab[geometry::Device::right_hand]);
      bool changed = first;
      for (const auto& in : inputs)
        if (const auto command = calibration_command(in, steps_.stage()))
          changed = steps_.apply(*command, tip) || changed;
      const std::string text = calibration_text(steps_, controls_);
      if (auto shown = scene_.set_text(text, lab[geometry::Device::head]); !shown) return shown.error();
      scene_.show(steps_, tip);
      submit(*timing, lab[geometry::Device::head], text);
      if (changed) screenshot();
      if (steps_.stage() == CalibrationStage::accepted) return result(true);
    }
  }

 private:
  bool stopped() const { return options_.stop_signal != nullptr && options_.stop_signal->load() != 0; }

  // This frame's inputs from every source; a quit from any of them (or the
  // display) ends the calibration, other signals change nothing here.
  io::Signal poll(std::vector<io::InputEvent>& inputs) {
    io::Signal signal = station_.display->poll_signal();
    for (io::ResponseSource* source : station_.responses)
      if (source->poll(inputs) == io::Signal::quit) signal = io::Signal::quit;
    return signal;
  }

  std::optional<Vec3> tip_of(const geometry::LabPose& hand) const {
    if (!geometry::usable(hand)) return std::nullopt;
    return hand.position_m + hand.orientation * options_.tip_offset_m;
  }

  void submit(const io::FrameTiming& timing, const geometry::LabPose& head, const std::string& text) {
    renderer::FrameDescription desc;
    desc.space = scene_.space();
    if (geometry::usable(head)) head_ = geometry::curved_from_rigid(desc.space, geometry::rigid_from_lab(head));
    desc.head = head_;
    desc.rig = station_.display->rig(timing, options_.ipd_m);
    desc.width_px = eye_size_.first;
    desc.height_px = eye_size_.second;
    station_.display->submit(scene_.scene(), desc, io::Overlay{io::Phase::calibration, text, true}, true);
  }

  void screenshot() {
    if (options_.screenshot_dir.empty()) return;
    std::string step(to_string(steps_.stage()));
    if (steps_.stage() == CalibrationStage::touching)
      step = "touch_" + std::string(kCornerNames[static_cast<std::size_t>(steps_.next_corner())]);
    char number[16];
    std::snprintf(number, sizeof number, "%02d", ++shots_);
    const auto stem = std::filesystem::path(options_.screenshot_dir) / ("calibration_" + std::string(number) + "_" + step);
    for (auto& file : station_.display->save_frame(stem.string())) result_.screenshots.push_back(std::move(file));
  }

  Result<CalibrationResult> ended() { return result(false); }

  CalibrationResult result(bool accepted) {
    result_.accepted = accepted;
    if (accepted) result_.fit = *steps_.fit();
    result_.touches_m = steps_.touches();
    result_.refusals = steps_.refusals();
    result_.redone = steps_.redone();
    return result_;
  }

  const io::Station& station_;
  const CalibrationOptions& options_;
  CalibrationSteps steps_;
  CalibrationScene scene_;
  CalibrationControls controls_;
  std::pair<std::uint32_t, std::uint32_t> eye_size_;
  Isometry head_ = Isometry::identity();
  CalibrationResult result_;
  int shots_ = 0;
};

}  // namespace

Result<CalibrationResult> run_calibration(const io::Station& station, const CalibrationOptions& options) {
  auto scene = CalibrationScene::build(options);
  if (!scene) return scene.error();
  try {
    CalibrationRun run(station, options, std::move(scene).value());
    return run.run();
  } catch (const io::DeviceFailure& f) {
    return Error{Error::Kind::api, std::string(f.what()) + " (during the table calibration)"};
  }
}

}  // namespace curvlab::harness::runner
