// Edge-position precision of bench_render_accuracy (section 4): how exactly
// the rendered pixels carry sub-pixel motions of the stimulus, per MSAA
// sample count. The stick scene (E3, tourist, 1 m stick 0.75 m ahead) is
// moved by steps far below a pixel — the head yawed in 0.01° steps, the stick
// bent in 0.1 mm steps — and features are estimated from the images alone by
// coverage-weighted sums in linear light:
//  * each end of the stick (yaw steps): along each row through the stick,
//    a reference column inside the stick gives the row's full coverage, and
//    the end lies at the reference column plus the summed coverage beyond it;
//  * the butt-to-shaft colour joint (bend steps): the same sum of the
//    fraction of butt colour between a butt and a shaft reference column a
//    few pixels either side of it;
//  * the stick's vertical centre at its middle (bend steps): the centroid of
//    the columns' coverage.
// Each feature's motion from the first step is compared with the motion of
// the analytic projection of the same point (E3 pinhole from the isometries
// in geometry/, not the renderer's view math); the residual is what the
// pixels get wrong. A constant bias of an estimator (the cap's shading, the
// silhouette of a cylinder) cancels in the motion.
#include "render_precision.hpp"
#include "bench_scenes.hpp"

#include "curvlab/geometry/isometry.hpp"
#include "curvlab/geometry/tube.hpp"
#include "curvlab/renderer/colour.hpp"
#include "curvlab/renderer/offscreen.hpp"
#include "curvlab/renderer/renderer.hpp"

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <vector>

namespace bench {
namespace {

using namespace curvlab;
using namespace curvlab::renderer;
using geometry::Vec3;

constexpr std::uint32_t kPx = 1024;  // per eye
constexpr double kFovRad = std::numbers::pi / 2.0;
constexpr double kIpdM = 0.063;
constexpr double kYawStepDeg = 0.01;
constexpr double kBendStepM = 0.0001;
constexpr int kSteps = 21;  // 0 … 20 steps: 0.2° of yaw, 2 mm of bend
// Where the stick scene puts the stick (renderer/src/scene.cpp, stick).
const Vec3 kStickAt{0.0, -0.25, -0.75};
// The joint between the butt's and the shaft's colours (mesh.hpp).
constexpr double kTransitionFraction = kStickButtFraction;
// The reference columns on either side of it, in px: close, so that neither
// the shading's slow change along the stick nor the images' 8-bit steps add
// up over many columns.
constexpr int kTransitionReachPx = 4;

// A world point in one eye's frame (E3: metres, the eye looking down −z).
glm::dvec4 in_eye(const Space& space, const Isometry& head, int eye, const geometry::Point& world) {
  const double side = eye == 0 ? -kIpdM / 2.0 : kIpdM / 2.0;
  const Isometry eye_pose = head * geometry::translation_m(space, Vec3(side, 0.0, 0.0));
  return glm::inverse(eye_pose.m) * world;
}

// The pixel position of a world point seen by one eye: E3 pinhole through the
// head and eye isometries (x right, y down, pixel centres at .5).
glm::dvec2 project(const Space& space, const Isometry& head, int eye, const geometry::Point& world) {
  const glm::dvec4 q = in_eye(space, head, eye, world);
  const double focal_px = (kPx / 2.0) / std::tan(kFovRad / 2.0);
  return {kPx / 2.0 + focal_px * q.x / -q.z, kPx / 2.0 - focal_px * q.y / -q.z};
}

// Linear relative luminance of each pixel (the images are sRGB-encoded).
std::vector<double> luminance(const Rgba8Image& img) {
  std::array<float, 256> decode{};
  for (std::size_t v = 0; v < decode.size(); ++v) decode[v] = srgb_to_linear(float(v) / 255.0f);
  std::vector<double> y(static_cast<std::size_t>(img.width) * img.height);
  for (std::size_t i = 0; i < y.size(); ++i)
    y[i] = relative_luminance({decode[img.pixels[4 * i]], decode[img.pixels[4 * i + 1]], decode[img.pixels[4 * i + 2]]});
  return y;
}

struct Luma {
  const std::vector<double>& y;
  double background;
  double at(int x, int row) const {
    return y[static_cast<std::size_t>(row) * kPx + static_cast<std::size_t>(x)] - background;
  }
};

// The rows the estimators read: those whose centres lie within the inner
// 60 % of the stick's projected thickness about y_px (placed from the sweep's
// first pose), all weighted alike. The same rows are read in every frame: the
// tube's ends and joints are seen along curves (each end's rim, each joint's
// circle), so a row entering or leaving the set would move the average.
constexpr double kStickRadiusM = 0.012;  // the protocol's (stimulus.stick_radius_m)

std::vector<int> inner_rows(double y_px, double distance_m) {
  const double half_px = kStickRadiusM * (kPx / 2.0) / std::tan(kFovRad / 2.0) / distance_m;
  std::vector<int> rows;
  for (int r = int(std::floor(y_px - half_px)); r <= int(std::ceil(y_px + half_px)); ++r)
    if (std::abs(r + 0.5 - y_px) <= 0.6 * half_px) rows.push_back(r);
  return rows;
}

// The end of the stick beyond column `ref` (inside it) in direction dir (±1).
double end_position(const Luma& l, int ref, int dir, const std::vector<int>& rows) {
  double sum = 0.0, weight = 0.0;
  for (const int r : rows) {
    const double w = l.at(ref, r);
    double covered = 0.0;
    for (int k = 1; k <= 40; ++k) covered += l.at(ref + dir * k, r) / w;
    // The reference pixel counts whole: the edge lies `covered` beyond it.
    const double end = dir > 0 ? ref + 1.0 + covered : ref - covered;
    sum += end;
    weight += 1.0;
  }
  return sum / weight;
}

// The butt-to-shaft transition between a butt column and a shaft column.
double transition_position(const Luma& l, int butt, int shaft, const std::vector<int>& rows) {
  double sum = 0.0, weight = 0.0;
  for (const int r : rows) {
    const double lo = l.at(butt, r), hi = l.at(shaft, r);
    double butt_part = 0.0;
    for (int x = butt + 1; x < shaft; ++x) butt_part += (hi - l.at(x, r)) / (hi - lo);
    sum += butt + 1.0 + butt_part;
    weight += 1.0;
  }
  return sum / weight;
}

// The stick's vertical coverage centroid over the columns x0 … x1.
double vertical_centre(const Luma& l, int x0, int x1, double y_px) {
  double sum = 0.0, weight = 0.0;
  for (int x = x0; x <= x1; ++x)
    for (int r = int(y_px) - 20; r <= int(y_px) + 20; ++r) {
      const double w = std::max(0.0, l.at(x, r));
      sum += w * (r + 0.5);
      weight += w;
    }
  return sum / weight;
}

struct Residuals {
  std::vector<double> px;
  void add(double measured_motion, double analytic_motion) { px.push_back(measured_motion - analytic_motion); }
  [[nodiscard]] double rms() const {
    double s = 0.0;
    for (double v : px) s += v * v;
    return px.empty() ? 0.0 : std::sqrt(s / double(px.size()));
  }
  [[nodiscard]] double max_abs() const {
    double m = 0.0;
    for (double v : px) m = std::max(m, std::abs(v));
    return m;
  }
};

StimulusScene stick_scene(double sagitta_m) { return scene_of(geometry::SpaceKind::E3, SceneKind::stick, sagitta_m); }

FrameDescription frame_of(const StimulusScene& s, const Isometry& head) {
  FrameDescription f;
  f.space = s.space;
  f.settings = ViewSettings::preset(ViewPreset::tourist);
  f.head = head;
  f.rig = StereoRig::from_ipd(kIpdM, Fov::symmetric(kFovRad, 1.0));
  f.width_px = kPx;
  f.height_px = kPx;
  return f;
}

geometry::Point stick_point(const Space& space, double sagitta_m, double u_m) {
  const geometry::BentStick stick{1.0, sagitta_m, kStickRadiusM};
  return geometry::translation_m(space, kStickAt).m * stick.centre_point(space, Isometry::identity(), u_m);
}

// The features of one frame, measured and analytic, per eye.
struct Features {
  std::array<double, 2> left_end{}, right_end{}, transition{}, middle_y{};
};

// Measures the features in the target's images. The estimators' windows are
// placed from the sweep's first pose (head, sagitta_m) and stay put while the
// stimulus moves under them, so a window never jumps by a pixel.
Features measure(const OffscreenTarget& target, const StimulusScene& s, const Isometry& head, double sagitta_m) {
  Features f;
  const double bg = relative_luminance(glm::vec3(palette::background));
  for (int e = 0; e < 2; ++e) {
    const auto y = luminance(target.image(static_cast<Eye>(e)));
    const Luma l{y, bg};
    const auto seen = [&](double u_m) {
      const geometry::Point p = stick_point(s.space, sagitta_m, u_m);
      return std::make_pair(project(s.space, head, e, p), -in_eye(s.space, head, e, p).z);
    };
    const auto [left, left_z] = seen(-0.5);
    const auto [right, right_z] = seen(0.5);
    const glm::dvec2 mid = project(s.space, head, e, stick_point(s.space, sagitta_m, 0.0));
    // Reference columns a few pixels inside each end's centre point: inside
    // the stick on every row (each end's rim reaches beyond that point) and
    // clear of the tip's colour joint, 2 cm in from the right end.
    f.left_end[e] = end_position(l, int(left.x) + 3, -1, inner_rows(left.y, left_z));
    f.right_end[e] = end_position(l, int(right.x) - 2, +1, inner_rows(right.y, right_z));
    const auto [joint, joint_z] = seen(-0.5 + kTransitionFraction);
    f.transition[e] = transition_position(l, int(joint.x) - kTransitionReachPx, int(joint.x) + kTransitionReachPx,
                                          inner_rows(joint.y, joint_z));
    f.middle_y[e] = vertical_centre(l, int(mid.x) - 3, int(mid.x) + 3, mid.y);
  }
  return f;
}

// Where the tube's cross-section circle at u_m is seen on the given rows, on
// average: the front half of the circle (the rim at an end, the joint's line
// round the stick) projected, and its x read at each row's centre. The
// estimators read an end or a joint along rows, and on each row the tube
// shows this circle's point, not the centre line's.
double circle_x(const Space& space, const Isometry& head, int eye, double sagitta_m, double u_m,
                const std::vector<int>& rows) {
  const glm::dvec4 c4 = in_eye(space, head, eye, stick_point(space, sagitta_m, u_m));
  const glm::dvec4 n4 = in_eye(space, head, eye, stick_point(space, sagitta_m, u_m + 1e-4));
  const glm::dvec3 c(c4), t = glm::normalize(glm::dvec3(n4) - c);
  const glm::dvec3 v = glm::normalize(-c);
  const glm::dvec3 toward = glm::normalize(v - glm::dot(v, t) * t);
  const glm::dvec3 side = glm::cross(t, toward);
  const double focal_px = (kPx / 2.0) / std::tan(kFovRad / 2.0);
  std::vector<glm::dvec2> curve;
  for (int i = -400; i <= 400; ++i) {
    const double phi = i / 400.0 * std::numbers::pi / 2.0;
    const glm::dvec3 p = c + kStickRadiusM * (std::cos(phi) * toward + std::sin(phi) * side);
    curve.emplace_back(kPx / 2.0 + focal_px * p.x / -p.z, kPx / 2.0 - focal_px * p.y / -p.z);
  }
  double sum = 0.0;
  int n = 0;
  for (const int r : rows) {
    const double y = r + 0.5;
    for (std::size_t i = 0; i + 1 < curve.size(); ++i) {
      const glm::dvec2 a = curve[i], b = curve[i + 1];
      if ((a.y - y) * (b.y - y) > 0.0 || a.y == b.y) continue;
      sum += a.x + (b.x - a.x) * (y - a.y) / (b.y - a.y);
      ++n;
      break;
    }
  }
  return sum / n;
}

// The analytic features: the ends and the joint where the tube shows them on
// the rows the estimators read (placed from the sweep's first pose), the
// middle's height from the centre line.
Features analytic(const StimulusScene& s, const Isometry& head, double sagitta_m, const Isometry& first_head) {
  Features f;
  for (int e = 0; e < 2; ++e) {
    const auto rows_at = [&](double u_m) {
      const geometry::Point p = stick_point(s.space, 0.0, u_m);
      return inner_rows(project(s.space, first_head, e, p).y, -in_eye(s.space, first_head, e, p).z);
    };
    f.left_end[e] = circle_x(s.space, head, e, sagitta_m, -0.5, rows_at(-0.5));
    f.right_end[e] = circle_x(s.space, head, e, sagitta_m, 0.5, rows_at(0.5));
    const double joint = -0.5 + kTransitionFraction;
    f.transition[e] = circle_x(s.space, head, e, sagitta_m, joint, rows_at(joint));
    f.middle_y[e] = project(s.space, head, e, stick_point(s.space, sagitta_m, 0.0)).y;
  }
  return f;
}

// The residuals of each kind of feature, and of all together.
struct SweepResiduals {
  Residuals ends, transition, middle, all;
  void add(Residuals& kind, double measured_motion, double analytic_motion) {
    kind.add(measured_motion, analytic_motion);
    all.add(measured_motion, analytic_motion);
  }
};

// Residuals of the motions over the yaw and the bend sweeps.
SweepResiduals sweep(const Context& ctx, std::uint32_t msaa) {
  Renderer r(ctx, RendererOptions{.msaa = msaa});
  OffscreenTarget target(ctx, kPx, kPx);
  SweepResiduals res;
  const StimulusScene straight = stick_scene(0.0);
  std::optional<Features> m0, a0;
  for (int i = 0; i < kSteps; ++i) {
    const double yaw = i * kYawStepDeg * std::numbers::pi / 180.0;
    const Isometry head = straight.head * geometry::rotation(Vec3(0, 1, 0), yaw);
    r.render(straight.scene, frame_of(straight, head), target);
    const Features m = measure(target, straight, straight.head, 0.0), a = analytic(straight, head, 0.0, straight.head);
    if (!m0) {
      m0 = m;
      a0 = a;
    }
    for (int e = 0; e < 2; ++e) {
      res.add(res.ends, m.left_end[e] - m0->left_end[e], a.left_end[e] - a0->left_end[e]);
      res.add(res.ends, m.right_end[e] - m0->right_end[e], a.right_end[e] - a0->right_end[e]);
    }
  }
  m0.reset();
  for (int i = 0; i < kSteps; ++i) {
    const double sagitta = i * kBendStepM;
    const StimulusScene s = stick_scene(sagitta);
    r.render(s.scene, frame_of(s, s.head), target);
    const Features m = measure(target, s, s.head, 0.0), a = analytic(s, s.head, sagitta, s.head);
    if (!m0) {
      m0 = m;
      a0 = a;
    }
    for (int e = 0; e < 2; ++e) {
      res.add(res.transition, m.transition[e] - m0->transition[e], a.transition[e] - a0->transition[e]);
      res.add(res.middle, m.middle_y[e] - m0->middle_y[e], a.middle_y[e] - a0->middle_y[e]);
    }
  }
  return res;
}

// Median frame time of the billiards scene (E3, native, both eyes, 1024²)
// per sample count, frames interleaved so machine load affects all alike.
std::vector<double> frame_times(const Context& ctx, const std::vector<std::uint32_t>& counts, int frames) {
  const StimulusScene s = scene_of(geometry::SpaceKind::E3, SceneKind::billiards);
  std::vector<std::unique_ptr<Renderer>> renderers;
  std::vector<std::unique_ptr<OffscreenTarget>> targets;
  for (const auto n : counts) {
    renderers.push_back(std::make_unique<Renderer>(ctx, RendererOptions{.msaa = n}));
    targets.push_back(std::make_unique<OffscreenTarget>(ctx, kPx, kPx));
  }
  std::vector<std::vector<double>> ms(counts.size());
  for (int i = 0; i < frames + 1; ++i)
    for (std::size_t k = 0; k < counts.size(); ++k) {
      FrameDescription f = frame_of(s, s.head * geometry::rotation(Vec3(0, 1, 0), 1e-6 * i));
      f.settings = ViewSettings::preset(ViewPreset::native);
      const FrameStats st = renderers[k]->render(s.scene, f, *targets[k]);
      if (i > 0) ms[k].push_back(st.frame_ms);
    }
  std::vector<double> out;
  for (auto& v : ms) {
    std::sort(v.begin(), v.end());
    out.push_back(v[v.size() / 2]);
  }
  return out;
}

}  // namespace

void print_precision_table(const Context& ctx, int frames, const PlainFrameMs& plain_ms) {
  // Pixels per degree at the image centre (1024 px over 90°).
  const double px_per_deg = (kPx / 2.0) / std::tan(kFovRad / 2.0) * std::numbers::pi / 180.0;
  const double arcsec_per_px = 3600.0 / px_per_deg;
  std::printf("\n4. Edge-position precision from pixels: stick (E3, tourist, 1024 x 1024 per eye, 90 deg,\n");
  std::printf("   %.2f px/deg at the centre); head yaw in %d steps of %.2f deg (both ends, both eyes) and\n",
              px_per_deg, kSteps - 1, kYawStepDeg);
  std::printf("   bend in %d steps of %.1f mm (colour transition, middle's height, both eyes); residual of\n",
              kSteps - 1, kBendStepM * 1e3);
  std::printf("   each feature's motion against the analytic projection; frame time: billiards, E3 native\n\n");
  std::printf("| msaa | samples used | residual RMS px | max px | RMS arcsec | max arcsec | ends RMS/max px | "
              "transition RMS/max px | middle RMS/max px | frame ms | ratio to msaa 1 | plain loop ms | "
              "plain ratio to msaa 1 | nothing drawn ms | nothing drawn ratio |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  const std::vector<std::uint32_t> counts{1, 2, 4, 8};
  const std::vector<double> ms = frame_times(ctx, counts, frames);
  std::vector<double> plain, empty;
  for (const auto n : counts) {
    plain.push_back(plain_ms(supported_msaa(ctx, n), false));
    empty.push_back(plain_ms(supported_msaa(ctx, n), true));
  }
  for (std::size_t k = 0; k < counts.size(); ++k) {
    const SweepResiduals s = sweep(ctx, counts[k]);
    const Residuals& r = s.all;
    std::printf("| %u | %u | %.4f | %.4f | %.2f | %.2f | %.3f/%.3f | %.3f/%.3f | %.3f/%.3f | %.1f | %.2f | %.1f | %.2f | %.1f | %.2f |\n",
                counts[k], supported_msaa(ctx, counts[k]), r.rms(), r.max_abs(), r.rms() * arcsec_per_px,
                r.max_abs() * arcsec_per_px, s.ends.rms(), s.ends.max_abs(), s.transition.rms(),
                s.transition.max_abs(), s.middle.rms(), s.middle.max_abs(), ms[k], ms[k] / ms[0], plain[k], plain[k] / plain[0], empty[k], empty[k] / empty[0]);
  }
}

}  // namespace bench
