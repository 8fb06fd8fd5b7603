// Stimulus kinds as one family (DESIGN.md §1): what a trial shows and what
// its judgement rests on. Each kind — the cue `stick`, the billiards `table`
// with its balls — is one class in one file under harness/src/runner/stimuli/,
// registered once in stimuli/registry.cpp, as the judgement types are
// (protocol/judgement.hpp). The trial scene, the perception model, `predict`,
// `preview`, the image observer and the session records ask the trial's
// kinds instead of naming them.
//
// A kind, from the trial's settings and world: adds its objects to the
// trial's scene (StimulusObjects), takes its share of the placement at onset
// (from the head at onset), follows every frame's curved-space poses (a
// rolling ball, a cue held in a hand), names the points an observer judges
// and the settings its records store.
//
// Kinds are stateless singletons: thread-safe. StimulusObjects are owned by
// one trial scene and are not thread-safe.
#pragma once

#include "curvlab/geometry/table.hpp"
#include "curvlab/geometry/tracking.hpp"
#include "curvlab/geometry/tube.hpp"
#include "curvlab/harness/protocol/settings.hpp"
#include "curvlab/renderer/scene.hpp"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string_view>
#include <vector>

namespace curvlab::harness::runner {

struct World {
  geometry::Space space;
  geometry::TableShape table;
  // Equal worlds share one tracker, so the edge correspondence survives
  // from trial to trial.
  [[nodiscard]] bool same_as(const World& other) const;
};

// The stimulus fixed at onset; each kind fills its share.
struct Placement {
  geometry::BentStick stick;
  geometry::Isometry stick_pose;  // model → world: chord along x, bow toward +z (the viewer)
  double table_sagitta_m = 0.0;
};

// A frame's curved-space poses of head, left hand and right hand, with
// whether each was tracked this frame (geometry/tracking.hpp).
using FramePoses = geometry::TrackingOutput;

// One kind's objects in one trial's scene. Every call edits only the
// objects this kind added.
class StimulusObjects {
 public:
  virtual ~StimulusObjects() = default;
  // Where the objects stand at onset (fixed for the trial unless update()
  // moves them).
  virtual void place(renderer::Scene& scene, const Placement& placement) = 0;
  // A changed stimulus during the trial (method of adjustment): shapes and
  // poses follow the settings.
  virtual void set_stimulus(renderer::Scene& scene, const protocol::Settings& s, const Placement& placement) = 0;
  // Every frame of the trial, before it is drawn: t_ns on the session clock
  // and the frame's curved-space poses. Today's kinds stand still.
  virtual void update(renderer::Scene& scene, std::int64_t t_ns, const FramePoses& poses) = 0;
  virtual void show(renderer::Scene& scene, bool visible) = 0;
};

class StimulusKind {
 public:
  virtual ~StimulusKind() = default;
  // The name the records store (conditions' "judged", predictions).
  [[nodiscard]] virtual std::string_view name() const = 0;
  // Whether a trial with settings `s` shows this kind.
  [[nodiscard]] virtual bool shown(const protocol::Settings& s) const = 0;

  // Its share of the placement at onset, from the head at onset.
  virtual void place(const World& world, const protocol::Settings& s, const geometry::Isometry& head_at_onset,
                     Placement& placement) const = 0;
  // Adds its objects, hidden, to the trial's scene.
  [[nodiscard]] virtual std::unique_ptr<StimulusObjects> build(renderer::Scene& scene, const World& world,
                                                               const protocol::Settings& s) const = 0;

  // The points a judgement of this kind rests on, and which of them the eyes
  // fixate.
  [[nodiscard]] virtual std::vector<geometry::Point> judged_points(const World& world,
                                                                   const Placement& placement) const = 0;
  [[nodiscard]] virtual std::size_t fixated_point(std::size_t points) const = 0;
  // The signed sagitta of the judged object from its judged points as
  // perceived (judged_points' order) and the map that perceived them.
  [[nodiscard]] virtual double perceived_sagitta_m(
      const World& world, std::vector<geometry::Vec3> judged_seen,
      const std::function<geometry::Vec3(const geometry::Point&)>& seen) const = 0;
  // The same for the physical stimulus (the null observer).
  [[nodiscard]] virtual double physical_sagitta_m(const protocol::Settings& s) const = 0;

  // The settings (dotted paths) that describe this kind in the stimulus
  // records of trials (protocol::settings_json, SettingsRecord::stimulus).
  [[nodiscard]] virtual std::vector<std::string_view> record_settings() const = 0;
};

// The kinds in the order they are judged first and built: the stick, then
// the table.
const std::vector<const StimulusKind*>& stimulus_kinds();
const StimulusKind& stick_stimulus_kind();
const StimulusKind& table_stimulus_kind();

// The kind a trial's judgement rests on: the first registered kind the
// trial shows; a trial that shows none is judged on the table, whose
// convexity is a setting even while hidden.
const StimulusKind& judged_kind(const protocol::Settings& s);
// Its position in stimulus_kinds() (a stable sort key).
std::size_t judged_index(const protocol::Settings& s);

}  // namespace curvlab::harness::runner
