#include "curvlab/harness/render_result.hpp"
#include "curvlab/harness/runner/image_observer.hpp"

#include "curvlab/harness/measure/stick.hpp"
#include "curvlab/harness/protocol/design.hpp"

#include <fstream>

namespace curvlab::harness::runner {

OnsetReader::OnsetReader(renderer::Context ctx) : ctx_(std::move(ctx)), renderer_(ctx_) {}

Result<std::unique_ptr<OnsetReader>> OnsetReader::create() {
  auto created = renderer::Context::create({.device = renderer::DeviceChoice::automatic, .validation = false});
  auto made = from_renderer(std::move(created), "the image observer needs a Vulkan device: ");
  if (!made) return made.error();
  return std::unique_ptr<OnsetReader>(new OnsetReader(std::move(made).value()));
}

namespace {

measure::StickScene stick_scene(const World& world, const protocol::Settings& s, const Placement& placement,
                                const OnsetView& view) {
  return {world.space,    perceived_preset(s), view.head,           view.rig,
          view.width_px,  view.height_px,      placement.stick,     placement.stick_pose,
          s.stimulus.stick_marks};
}

}  // namespace

Result<Done> write_onset_record(const std::string& path, const World& world, const protocol::Settings& s,
                                const Placement& placement, const OnsetView& view) {
  if (!stick_stimulus_kind().shown(s)) return Done{};
  std::ofstream out(path);
  out << measure::scene_json(stick_scene(world, s, placement, view)).dump(2) << '\n';
  if (!out) return Error{Error::Kind::io, "cannot write " + path};
  return Done{};
}

Result<std::optional<Percept>> OnsetReader::read(const World& world, const protocol::Settings& s,
                                                 const Placement& placement, const OnsetView& view,
                                                 const ObserverParams& observer) {
  if (&judged_kind(s) != &stick_stimulus_kind()) return std::optional<Percept>{};
  if (!target_ || target_->image(renderer::Eye::left).width != static_cast<int>(view.width_px) ||
      target_->image(renderer::Eye::left).height != static_cast<int>(view.height_px))
    target_.emplace(ctx_, view.width_px, view.height_px);
  renderer::Scene scene;
  scene.add(renderer::stick_object(world.space, placement.stick, placement.stick_pose, s.stimulus.stick_marks));
  renderer::FrameDescription frame{world.space, view.settings, view.head, view.rig, view.width_px, view.height_px};
  renderer_.render(scene, frame, *target_);
  auto estimate = measure::measure_stick(target_->image(renderer::Eye::left),
                                         target_->image(renderer::Eye::right),
                                         stick_scene(world, s, placement, view), &observer.vision);
  if (!estimate) return Error{estimate.error().kind, "image observer: " + estimate.error().message};
  if (!estimate->human) return std::optional<Percept>(without_disparity(observer));  // one eye
  return std::optional<Percept>(human_percept(*estimate->human, estimate->estimated_sagitta_m, observer));
}

Result<Done> check_image_observer(const protocol::Protocol& p) {
  const protocol::Design design = protocol::expand_design(p, 1);
  for (const auto& t : design.trials)
    if (&judged_kind(t.settings) == &stick_stimulus_kind() && geometry::binocular(perceived_preset(t.settings)) &&
        t.settings.stimulus.stick_marks != renderer::StickMarks::rings)
      return Error{Error::Kind::usage,
                   "--observer image reads the stick's rings from the images, but block '" + t.block +
                       "' shows a plain stick: set stimulus.stick_marks = \"rings\" (docs/protocols.md)"};
  return Done{};
}

}  // namespace curvlab::harness::runner
