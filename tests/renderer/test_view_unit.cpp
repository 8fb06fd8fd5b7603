// Pure tests of the renderer's math and plan (no device). Oracles are
// independent closed forms in long double, written here, not calls back into
// the code under test.
#include "stimulus_fixtures.hpp"
#include "../support/png_files.hpp"

#include "curvlab/geometry/maps.hpp"
#include "curvlab/renderer/colour.hpp"
#include "curvlab/renderer/image_io.hpp"
#include "curvlab/renderer/plan.hpp"
#include "curvlab/renderer/tiling.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>
#include <numbers>

using namespace curvlab;
using namespace curvlab::renderer;
using curvlab::renderer::fixtures::frame_for;
using curvlab::renderer::fixtures::make;
using curvlab::renderer::fixtures::make_from;
using curvlab::renderer::fixtures::SceneKind;
using curvlab::renderer::fixtures::settings_in;
using curvlab::renderer::fixtures::StimulusScene;
using geometry::SpaceKind;

namespace {

constexpr long double kPiL = 3.141592653589793238462643383279502884L;



// A point straight ahead (−z) at distance d metres, in long double.
geometry::Point ahead(SpaceKind kind, long double rho, long double d) {
  const long double t = d / rho;
  switch (kind) {
    case SpaceKind::S3: return {0.0, 0.0, double(-rho * std::sin(t)), double(rho * std::cos(t))};
    case SpaceKind::H3: return {0.0, 0.0, double(-rho * std::sinh(t)), double(rho * std::cosh(t))};
    case SpaceKind::E3: return {0.0, 0.0, double(-d), double(rho)};
  }
  return {};
}

}  // namespace

TEST(ViewMath, NativeDepthIsTheGeodesicDistance) {
  // Native view: a point straight ahead at d metres lands at Euclidean depth
  // d (front) and, in S3, at 2πρ − d through the antipode (back).
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    const double rho = 0.7;
    const geometry::Space space{kind, rho};
    ViewSettings settings = ViewSettings::preset(ViewPreset::native);
    EyeOffset eye;  // at the nose
    const ViewConstants v = make_view_constants(space, settings, Isometry::identity(), eye);
    for (long double d : {0.1L, 0.5L, 1.3L, 2.0L}) {
      if (kind == SpaceKind::S3 && d / rho >= kPiL) continue;
      const geometry::Point p = ahead(kind, rho, d);
      const glm::dvec4 clip = clip_position(v, Hemisphere::front, p);
      EXPECT_NEAR(clip.w, double(d), 1e-12) << geometry::to_string(kind) << " d=" << double(d);
      EXPECT_NEAR(clip.x, 0.0, 1e-12);
      if (kind == SpaceKind::S3) {
        const glm::dvec4 back = clip_position(v, Hemisphere::back, p);
        // Seen behind (+z): clip.w = −z is negative, |z| = 2πρ − d.
        EXPECT_NEAR(back.w, double(-(2.0L * kPiL * rho - d)), 1e-12);
      }
    }
  }
}

TEST(ViewMath, TouristDepthIsMonotonicAndSplitInS3) {
  // w/|z| falls with distance in every space, so projective depth rises;
  // S3 front content stays in [0, ½] and the back hemisphere in [½, 1].
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    const double rho = 0.8;
    const geometry::Space space{kind, rho};
    const ViewConstants v = make_view_constants(space, ViewSettings::preset(ViewPreset::tourist),
                                                Isometry::identity(), EyeOffset{});
    double last = -1.0;
    const double max_d = kind == SpaceKind::S3 ? 0.98 * std::numbers::pi * rho : 8.0;
    for (double d = 0.06; d < max_d; d += 0.05) {
      const glm::dvec4 clip = clip_position(v, Hemisphere::front, ahead(kind, rho, d));
      const double depth = clip.z / clip.w;
      EXPECT_GT(depth, last) << geometry::to_string(kind) << " d=" << d;
      EXPECT_GE(depth, 0.0);
      EXPECT_LE(depth, kind == SpaceKind::S3 ? 0.5 : 1.0);
      last = depth;
      if (kind == SpaceKind::S3) {
        // The twin −p of a point behind the viewer is ahead.
        const geometry::Point behind = ahead(kind, rho, d) * glm::dvec4(1, 1, -1, 1);
        const glm::dvec4 b = clip_position(v, Hemisphere::back, behind);
        EXPECT_GT(b.w, 0.0);
        EXPECT_GE(b.z / b.w, 0.5);
        EXPECT_LE(b.z / b.w, 1.0);
      }
    }
  }
}

TEST(ViewMath, AsymmetricFovMapsItsEdgesToTheViewportEdges) {
  const Fov fov{-0.9, 0.6, 0.5, -0.8};  // as an OpenXR runtime reports
  const glm::dmat4 m = projection_matrix(fov, 10.0, 0.0, 0.0, 1.0);
  auto ndc = [&](double ax, double ay) {
    const glm::dvec4 c = m * glm::dvec4(std::tan(ax), std::tan(ay), -1.0, 0.1);
    return glm::dvec2(c.x / c.w, c.y / c.w);
  };
  EXPECT_NEAR(ndc(fov.angle_left_rad, 0).x, -1.0, 1e-12);
  EXPECT_NEAR(ndc(fov.angle_right_rad, 0).x, 1.0, 1e-12);
  EXPECT_NEAR(ndc(0, fov.angle_up_rad).y, -1.0, 1e-12);  // Vulkan: up is −y
  EXPECT_NEAR(ndc(0, fov.angle_down_rad).y, 1.0, 1e-12);
}

TEST(Subdivision, TouristKeepsGeodesicsStraightNativeBendsThem) {
  // The table's edges are geodesics. Drawn as one straight piece, the
  // tourist projection is exact (a linear map of R⁴ takes the geodesic's
  // plane to a line), while the native log map bends them by pixels and the
  // plan subdivides until the error budget holds.
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::H3}) {
    const StimulusScene s = make(kind, SceneKind::table);
    const auto& table = s.scene.objects()[0];
    const FrameDescription tourist = frame_for(s, ViewPreset::tourist);
    const FrameDescription native = frame_for(s, ViewPreset::native);
    const ViewConstants vt = make_view_constants(s.space, tourist.settings, s.head, tourist.rig.eyes[0]);
    const ViewConstants vn = make_view_constants(s.space, native.settings, s.head, native.rig.eyes[0]);
    double tourist_err = 0.0;
    double native_err = 0.0;
    for (const auto& e : table.info.long_edges) {
      tourist_err = std::max(tourist_err, edge_screen_error(vt, Hemisphere::front,
                                                            vt.viewer_from_world.m, e, 1, 1024, 1024).max_px);
      native_err = std::max(native_err, edge_screen_error(vn, Hemisphere::front,
                                                          vn.viewer_from_world.m, e, 1, 1024, 1024).max_px);
    }
    EXPECT_LT(tourist_err, 1e-6) << geometry::to_string(kind);
    EXPECT_GT(native_err, 0.5) << geometry::to_string(kind);

    const RenderPlan pt = plan_frame(s.scene, tourist);
    const RenderPlan pn = plan_frame(s.scene, native);
    EXPECT_EQ(pt.max_level, 0);
    EXPECT_GT(pn.max_level, 0);
    for (const auto& v : pn.views) EXPECT_LE(v.estimated_error_px, native.settings.error_budget_px);
  }
  // E3: the log map is the identity, nothing bends.
  const StimulusScene e3 = make(SpaceKind::E3, SceneKind::table);
  EXPECT_EQ(plan_frame(e3.scene, frame_for(e3, ViewPreset::native)).max_level, 0);
}

TEST(Plan, MonocularPlansOneView) {
  const StimulusScene s = make(SpaceKind::H3, SceneKind::billiards);
  FrameDescription f = frame_for(s, ViewPreset::monocular);
  const RenderPlan p = plan_frame(s.scene, f);
  EXPECT_EQ(p.rendered_views(), 1);
  EXPECT_TRUE(p.views[static_cast<int>(f.settings.dominant_eye)].rendered);
  f.settings.eyes = EyeSelection::left;
  const RenderPlan left = plan_frame(s.scene, f);
  EXPECT_TRUE(left.views[0].rendered);
  EXPECT_FALSE(left.views[1].rendered);
  EXPECT_TRUE(left.views[1].draws.empty());
}

TEST(Plan, BackHemisphereOnlyInS3AndOnlyWhenVisible) {
  for (SpaceKind kind : {SpaceKind::E3, SpaceKind::H3})
    for (SceneKind scene : {SceneKind::billiards, SceneKind::tiling})
      for (double yaw : {0.0, std::numbers::pi})
        for (ViewPreset v : {ViewPreset::tourist, ViewPreset::native}) {
          const StimulusScene s = make(kind, scene, yaw);
          const RenderPlan p = plan_frame(s.scene, frame_for(s, v));
          EXPECT_FALSE(p.back_hemisphere);
          for (const auto& view : p.views)
            for (const auto& d : view.draws) EXPECT_EQ(d.hemisphere, Hemisphere::front);
        }
  // S3 looking away from the table: its antipodal image is ahead.
  const StimulusScene away = make(SpaceKind::S3, SceneKind::billiards, std::numbers::pi);
  for (ViewPreset v : {ViewPreset::tourist, ViewPreset::native}) {
    FrameDescription f = frame_for(away, v);
    EXPECT_TRUE(plan_frame(away.scene, f).back_hemisphere);
    f.settings.back_hemisphere = false;  // the confound control
    EXPECT_FALSE(plan_frame(away.scene, f).back_hemisphere);
  }
  // The stick scene in S3: the stick is ahead, its antipodal image behind
  // the viewer and out of view, so no back pass is planned for it. (The
  // prompt panel, 1.5 m ahead and past the equator ρπ/2 = 1 m, has a bound
  // too large for the plan to rule its antipodal image out: it is hidden.)
  StimulusScene stick = make(SpaceKind::S3, SceneKind::stick);
  for (std::size_t i = 0; i < stick.scene.objects().size(); ++i)
    if (stick.scene.objects()[i].name != "cue stick") stick.scene.edit(i).visible = false;
  EXPECT_FALSE(plan_frame(stick.scene, frame_for(stick, ViewPreset::tourist)).back_hemisphere);
}

TEST(Plan, CullsObjectsOutsideTheView) {
  const StimulusScene s = make(SpaceKind::E3, SceneKind::billiards, std::numbers::pi);
  const RenderPlan p = plan_frame(s.scene, frame_for(s, ViewPreset::tourist));
  EXPECT_GT(p.views[0].culled, 0);
  EXPECT_LT(p.views[0].draws.size(), s.scene.objects().size());
}

TEST(Table, CornersCloseWithRightAngles) {
  // Independent oracle: consecutive corners are side_rad apart (chord form in
  // long double) and the angle between the two edges at each corner is 90°.
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    const StimulusScene s = make(kind, SceneKind::table);
    const auto& edges = s.scene.objects()[0].info.long_edges;
    const long double rho = s.space.radius_m;
    const long double k = s.space.k();
    auto pform = [&](const geometry::Point& a, const geometry::Point& b) {
      using L = long double;
      return k * (L{a.x} * L{b.x} + L{a.y} * L{b.y} + L{a.z} * L{b.z}) + L{a.w} * L{b.w};
    };
    // Tangent at p toward q: q − P(p,q)/ρ² p; angle from g = xyz·xyz + k w·w.
    auto tangent = [&](const geometry::Point& p, const geometry::Point& q) {
      const long double f = pform(p, q) / (rho * rho);
      return std::array<long double, 4>{q.x - f * p.x, q.y - f * p.y, q.z - f * p.z, q.w - f * p.w};
    };
    auto gform = [&](const std::array<long double, 4>& a, const std::array<long double, 4>& b) {
      return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + k * a[3] * b[3];
    };
    ASSERT_EQ(edges.size(), static_cast<std::size_t>(geometry::default_table_sides(kind)));
    for (std::size_t i = 0; i < edges.size(); ++i) {
      const auto& next = edges[(i + 1) % edges.size()];
      EXPECT_NEAR(edges[i].b.x, next.a.x, 1e-9);
      EXPECT_NEAR(edges[i].b.z, next.a.z, 1e-9);
      const auto t1 = tangent(edges[i].b, edges[i].a);
      const auto t2 = tangent(edges[i].b, next.b);
      const long double c = gform(t1, t2) / std::sqrt(gform(t1, t1) * gform(t2, t2));
      EXPECT_NEAR(double(c), 0.0, 1e-9) << geometry::to_string(kind) << " corner " << i;
      // Edge length: the protocol's physical edge (table.edge_m, 1 m), in E3 too.
      const auto& a = edges[i].a;
      const auto& b = edges[i].b;
      const long double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z, dw = a.w - b.w;
      const long double chord = std::sqrt(dx * dx + dy * dy + dz * dz + k * dw * dw);
      const long double len = kind == SpaceKind::S3 ? 2 * rho * std::asin(chord / (2 * rho))
                              : kind == SpaceKind::H3 ? 2 * rho * std::asinh(chord / (2 * rho))
                                                      : chord;
      EXPECT_NEAR(double(len), settings_in(kind).table.edge_m, 1e-9);
    }
  }
}

TEST(Tiling, HoneycombsHaveTheirCellsAndAngles) {
  const geometry::Space s3{SpaceKind::S3, 1.0};
  const Tiling t = build_tiling(s3);
  EXPECT_EQ(t.cells, 120u);    // the 120-cell
  EXPECT_EQ(t.edges.size(), 1200u);
  // Oracle for the cell circumradius R (mpmath, 30 digits): at a vertex three
  // faces with face angle α meet at dihedral δ, cos δ = cos α/(1 + cos α);
  // the face's circumradius r follows from C(r) = cot(π/5)·cot(α/2)-type
  // rules, and S(R) = S(r)/sin ψ with ψ the Euclidean dodecahedron's angle
  // between a face centre and its vertices.
  EXPECT_NEAR(regular_cell_dihedral_rad(s3, 5, t.cell_circumradius_rad), 2.0 * std::numbers::pi / 3.0, 1e-9);
  EXPECT_NEAR(t.cell_circumradius_rad, 0.388139515370188763, 1e-9);
  const geometry::Space h3{SpaceKind::H3, 1.0};
  const Tiling th = build_tiling(h3);
  EXPECT_NEAR(regular_cell_dihedral_rad(h3, 5, th.cell_circumradius_rad), std::numbers::pi / 2.0, 1e-9);
  // {5,3,4}: the right-angled dodecahedron (same oracle, ρ = 1).
  EXPECT_NEAR(th.cell_circumradius_rad, 1.22645687125140588, 1e-9);
  EXPECT_GT(th.cells, 40u);
  const geometry::Space e3{SpaceKind::E3, 1.0};
  const Tiling te = build_tiling(e3);
  EXPECT_EQ(te.p, 4);
  EXPECT_NEAR(regular_cell_dihedral_rad(e3, 4, te.cell_circumradius_rad), std::numbers::pi / 2.0, 1e-12);
  // Every edge of the cubic honeycomb is 1 m long.
  for (const auto& e : te.edges) EXPECT_NEAR(glm::length(e.a - e.b), 1.0, 1e-9);
}

TEST(Text, RendersInkIntoThePanel) {
  auto bmp = render_text("Straight?\nyes / no", 256, 96, 40.0, CURVLAB_DEFAULT_FONT);
  ASSERT_TRUE(std::holds_alternative<CoverageBitmap>(bmp));
  const auto& b = std::get<CoverageBitmap>(bmp);
  int ink = 0;
  for (auto v : b.pixels) ink += v > 128;
  EXPECT_GT(ink, 300);
  EXPECT_LT(ink, 256 * 96 / 2);
  auto missing = render_text("x", 16, 16, 10.0, "/nonexistent/font.ttf");
  ASSERT_TRUE(std::holds_alternative<RenderError>(missing));
  EXPECT_NE(std::get<RenderError>(missing).message.find("/nonexistent/font.ttf"), std::string::npos);
}

// Settings that give no table, and a prompt font that cannot be read, come
// back from the scene builder as errors of their own kinds (the harness
// tells a person to fix the protocol for one and the installation for the
// other).
TEST(StimulusScene, ImpossibleSettingsAndAMissingFontAreErrorsOfTheirKind) {
  auto no_table = settings_in(SpaceKind::H3);
  no_table.table.edge_m = -1.0;
  const auto impossible = harness::runner::viewed_scene(SceneKind::table, no_table, {}, "", CURVLAB_DEFAULT_FONT);
  ASSERT_FALSE(impossible);
  EXPECT_EQ(impossible.error().kind, harness::Error::Kind::bad_input);
  EXPECT_NE(impossible.error().message.find("edge length"), std::string::npos) << impossible.error().message;

  const auto unreadable = harness::runner::viewed_scene(SceneKind::stick, settings_in(SpaceKind::E3), {}, "prompt",
                                                        "/nonexistent/font.ttf");
  ASSERT_FALSE(unreadable);
  EXPECT_EQ(unreadable.error().kind, harness::Error::Kind::io);
  EXPECT_NE(unreadable.error().message.find("/nonexistent/font.ttf"), std::string::npos);
}

// ---- colour --------------------------------------------------------------

TEST(Colour, SrgbTransferRoundTripsAndMatchesTheStandard) {
  // IEC 61966-2-1: 0.5 encodes 0.2140 linear; the curve's two pieces meet.
  EXPECT_NEAR(srgb_to_linear(0.5f), 0.21404, 1e-4);
  EXPECT_NEAR(srgb_to_linear(0.04045f), 0.04045f / 12.92f, 1e-6);
  for (int i = 0; i <= 255; ++i) {
    const float v = float(i) / 255.0f;
    EXPECT_NEAR(linear_to_srgb(srgb_to_linear(v)), v, 1e-5) << i;
  }
}

TEST(Colour, PhotometryTableInTheDocsMatchesThePalette) {
  // docs/renderer.md, "Photometry": relative luminance Y of each colour.
  const std::vector<std::pair<glm::vec4, double>> documented = {
      {palette::background, 0.0014}, {palette::cloth, 0.1099},      {palette::cushion, 0.0708},
      {palette::rail, 0.0766},       {palette::skirt, 0.0336},      {palette::stick_butt, 0.0159},
      {palette::stick_shaft, 0.4379}, {palette::stick_tip, 0.7846}, {palette::text_ink, 0.9054},
      {palette::text_paper, 0.0060}};
  for (const auto& [colour, y] : documented) EXPECT_NEAR(relative_luminance(glm::vec3(colour)), y, 1e-4);
}

TEST(ImageIo, PngsCarryAnSrgbChunkAndRoundTrip) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("curvlab_png_" + std::to_string(::getpid()) + ".png");
  Rgba8Image img{3, 2, {}};
  for (int i = 0; i < 24; ++i) img.pixels.push_back(static_cast<std::uint8_t>(i * 10));
  ASSERT_TRUE(test::png_written(write_png(path.string(), img)));
  std::ifstream in(path, std::ios::binary);
  std::stringstream contents;
  contents << in.rdbuf();
  const std::string bytes = contents.str();
  EXPECT_NE(bytes.find("sRGB"), std::string::npos);
  EXPECT_NE(bytes.find("gAMA"), std::string::npos);
  Rgba8Image back;
  ASSERT_TRUE(test::read_png_into(path.string(), back));
  EXPECT_EQ(back.pixels, img.pixels);
  std::filesystem::remove(path);
  const auto refused = write_png("/nonexistent-dir/x.png", img);
  ASSERT_TRUE(std::holds_alternative<RenderError>(refused));
  EXPECT_EQ(std::get<RenderError>(refused).kind, RenderError::Kind::file);
  EXPECT_NE(std::get<RenderError>(refused).message.find("/nonexistent-dir/x.png"), std::string::npos);
  const auto unread = read_png("/nonexistent-dir/x.png");
  ASSERT_TRUE(std::holds_alternative<RenderError>(unread));
  EXPECT_EQ(std::get<RenderError>(unread).kind, RenderError::Kind::file);
  EXPECT_NE(std::get<RenderError>(unread).message.find("/nonexistent-dir/x.png"), std::string::npos);
}
