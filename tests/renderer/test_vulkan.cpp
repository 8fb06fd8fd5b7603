// Device tests on lavapipe (label "vulkan"), validation layer on: any
// validation message fails the test.
#include "stimulus_fixtures.hpp"
#include "../support/panel_ink.hpp"
#include "../support/png_files.hpp"

#include "curvlab/renderer/colour.hpp"
#include "curvlab/renderer/mesh.hpp"
#include "curvlab/renderer/offscreen.hpp"
#include "curvlab/renderer/renderer.hpp"
#include "curvlab/renderer/shader.hpp"

#include "curvlab/geometry/maps.hpp"
#include "curvlab/geometry/tube.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

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

class VulkanTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto created = Context::create({.device = DeviceChoice::software, .validation = true});
    if (auto* e = std::get_if<RenderError>(&created)) FAIL() << e->message;
    ctx_ = std::make_unique<Context>(std::move(std::get<Context>(created)));
  }
  void TearDown() override {
    if (!ctx_) return;
    const auto messages = ctx_->validation_log().messages();
    EXPECT_EQ(messages.size(), 0u) << (messages.empty() ? "" : messages.front());
  }
  const Context& ctx() const { return *ctx_; }

  std::unique_ptr<Context> ctx_;
};



// True when every pixel equals the first (the cleared background).
bool all_background(const Rgba8Image& img) {
  for (std::size_t i = 4; i < img.pixels.size(); i += 4)
    for (std::size_t c = 0; c < 4; ++c)
      if (img.pixels[i + c] != img.pixels[c]) return false;
  return true;
}

Rgba8Image side_by_side(const Rgba8Image& a, const Rgba8Image& b) {
  Rgba8Image out{a.width + b.width, a.height, {}};
  out.pixels.resize(static_cast<std::size_t>(out.width * out.height * 4));
  for (int y = 0; y < a.height; ++y) {
    std::copy_n(&a.pixels[static_cast<std::size_t>(y * a.width * 4)], a.width * 4,
                &out.pixels[static_cast<std::size_t>(y * out.width * 4)]);
    std::copy_n(&b.pixels[static_cast<std::size_t>(y * b.width * 4)], b.width * 4,
                &out.pixels[static_cast<std::size_t>((y * out.width + a.width) * 4)]);
  }
  return out;
}

}  // namespace

// ---- golden images: every space × view, both eyes side by side ----------

struct GoldenCase {
  SpaceKind space;
  ViewPreset view;
};

class Golden : public VulkanTest, public ::testing::WithParamInterface<GoldenCase> {};

TEST_P(Golden, MatchesApprovedImage) {
  const auto [kind, preset] = GetParam();
  const std::string name = std::string(geometry::to_string(kind)) + "_" + std::string(to_string(preset));
  const StimulusScene s = make(kind, SceneKind::billiards);
  Renderer renderer(ctx());
  OffscreenTarget target(ctx(), 256, 256);
  const FrameStats stats = renderer.render(s.scene, frame_for(s, preset, 256), target);
  EXPECT_GT(stats.draws, 0);
  const Rgba8Image actual = side_by_side(target.image(Eye::left), target.image(Eye::right));

  // Every run leaves its output where approve_goldens picks it up.
  const std::filesystem::path out_dir = CURVLAB_GOLDEN_OUT_DIR;
  std::filesystem::create_directories(out_dir / "diff");
  ASSERT_TRUE(test::png_written(write_png((out_dir / (name + ".png")).string(), actual)));

  const std::filesystem::path golden = std::filesystem::path(CURVLAB_GOLDEN_DIR) / (name + ".png");
  Rgba8Image expected;
  ASSERT_TRUE(test::read_png_into(golden.string(), expected))
      << "\nnew output: " << (out_dir / (name + ".png")).string()
      << "\nlook at it, then run: cmake --build <build> --target approve_goldens";
  // Tolerance: a channel may differ by 6/255, and 0.3 % of pixels by more
  // (other drivers rasterise edges slightly differently; lavapipe itself is
  // byte-identical run to run).
  const ImageDiff d = diff_images(actual, expected, 6);
  const int allowed = actual.width * actual.height * 3 / 1000;
  if (d.differing_pixels > allowed) {
    const auto diff_path = out_dir / "diff" / (name + ".diff.png");
    // The diff image is a help for the person reading the failure below,
    // which is reported whether or not it could be written.
    (void)write_png(diff_path.string(), d.visual);
    ADD_FAILURE() << name << ": " << d.differing_pixels << " pixels differ (allowed " << allowed
                  << ", max channel difference " << d.max_channel_diff << ")\n"
                  << "diff image: " << diff_path.string() << "\nnew output: "
                  << (out_dir / (name + ".png")).string()
                  << "\nif the change is intended: cmake --build <build> --target approve_goldens";
  }
}

INSTANTIATE_TEST_SUITE_P(
    SpacesAndViews, Golden,
    ::testing::Values(GoldenCase{SpaceKind::S3, ViewPreset::tourist}, GoldenCase{SpaceKind::S3, ViewPreset::native},
                      GoldenCase{SpaceKind::S3, ViewPreset::monocular}, GoldenCase{SpaceKind::E3, ViewPreset::tourist},
                      GoldenCase{SpaceKind::E3, ViewPreset::native}, GoldenCase{SpaceKind::E3, ViewPreset::monocular},
                      GoldenCase{SpaceKind::H3, ViewPreset::tourist}, GoldenCase{SpaceKind::H3, ViewPreset::native},
                      GoldenCase{SpaceKind::H3, ViewPreset::monocular}),
    [](const ::testing::TestParamInfo<GoldenCase>& param_info) {
      return std::string(geometry::to_string(param_info.param.space)) + "_" +
             std::string(to_string(param_info.param.view));
    });

// ---- the skipping -------------------------------------------------------

TEST_F(VulkanTest, MonocularRendersOneViewAndTheOtherEyeIsBackground) {
  const StimulusScene s = make(SpaceKind::H3, SceneKind::billiards);
  Renderer renderer(ctx());
  OffscreenTarget target(ctx(), 128, 128);
  FrameDescription f = frame_for(s, ViewPreset::monocular, 128);
  f.settings.dominant_eye = Eye::left;
  const FrameStats stats = renderer.render(s.scene, f, target);
  EXPECT_EQ(stats.views, 1);
  EXPECT_EQ(stats.passes, 1);
  EXPECT_TRUE(all_background(target.image(Eye::right)));
  EXPECT_FALSE(all_background(target.image(Eye::left)));

  const FrameStats both = renderer.render(s.scene, frame_for(s, ViewPreset::native, 128), target);
  EXPECT_EQ(both.views, 2);
  EXPECT_EQ(both.draws, 2 * stats.draws);
}

TEST_F(VulkanTest, UnchangedHeadlessFrameIsNotRenderedAgain) {
  StimulusScene s = make(SpaceKind::E3, SceneKind::billiards);
  Renderer renderer(ctx());
  OffscreenTarget target(ctx(), 96, 96);
  const FrameDescription f = frame_for(s, ViewPreset::native, 96);
  const FrameStats first = renderer.render(s.scene, f, target);
  EXPECT_FALSE(first.reused);
  const Rgba8Image before = target.image(Eye::left);
  const FrameStats second = renderer.render(s.scene, f, target);
  EXPECT_TRUE(second.reused);
  EXPECT_EQ(second.passes, 0);
  EXPECT_EQ(second.draws, 0);
  EXPECT_EQ(target.image(Eye::left).pixels, before.pixels);
  // Moving the cue ball (the first ball) is a change: drawn again, and the
  // image differs.
  std::size_t cue = 0;
  while (s.scene.objects().at(cue).name != "ball") ++cue;
  s.scene.edit(cue).pose = s.scene.objects()[cue].pose *
                           geometry::translation_m(s.space, geometry::Vec3(0.1, 0.0, -0.1));
  const FrameStats third = renderer.render(s.scene, f, target);
  EXPECT_FALSE(third.reused);
  EXPECT_GT(third.draws, 0);
  EXPECT_NE(target.image(Eye::left).pixels, before.pixels);
  // A different target with the same frame is not "unchanged" either.
  OffscreenTarget other(ctx(), 96, 96);
  EXPECT_FALSE(renderer.render(s.scene, f, other).reused);
}

TEST_F(VulkanTest, BackHemisphereOnlyInS3) {
  Renderer renderer(ctx());
  OffscreenTarget target(ctx(), 96, 96);
  for (SpaceKind kind : {SpaceKind::E3, SpaceKind::H3}) {
    for (SceneKind scene : {SceneKind::billiards, SceneKind::tiling}) {
      const StimulusScene s = make(kind, scene, std::numbers::pi);
      EXPECT_FALSE(renderer.render(s.scene, frame_for(s, ViewPreset::tourist, 96), target).back_hemisphere);
      EXPECT_FALSE(renderer.render(s.scene, frame_for(s, ViewPreset::native, 96), target).back_hemisphere);
    }
  }
  // S3 looking away from the table: the antipodal image is drawn and shows;
  // switched off, it is neither drawn nor seen.
  const StimulusScene s = make(SpaceKind::S3, SceneKind::billiards, std::numbers::pi);
  FrameDescription f = frame_for(s, ViewPreset::native, 96);
  const FrameStats on = renderer.render(s.scene, f, target);
  EXPECT_TRUE(on.back_hemisphere);
  EXPECT_FALSE(all_background(target.image(Eye::left)));
  f.settings.back_hemisphere = false;
  const FrameStats off = renderer.render(s.scene, f, target);
  EXPECT_FALSE(off.back_hemisphere);
  EXPECT_LT(off.draws, on.draws);
}

TEST_F(VulkanTest, NativeSubdividesTouristDoesNot) {
  const StimulusScene s = make(SpaceKind::H3, SceneKind::table);
  Renderer renderer(ctx());
  OffscreenTarget target(ctx(), 256, 256);
  const FrameStats tourist = renderer.render(s.scene, frame_for(s, ViewPreset::tourist, 256), target);
  const FrameStats native = renderer.render(s.scene, frame_for(s, ViewPreset::native, 256), target);
  EXPECT_EQ(tourist.max_level, 0);
  EXPECT_GT(native.max_level, 0);
  EXPECT_GT(native.triangles, tourist.triangles);
  EXPECT_LE(native.error_px, 0.1);
}

// ---- GLSL vs C++ --------------------------------------------------------

namespace {

// A compute shader of renderer/shaders/ (local size 64) whose set 0 holds
// one buffer per binding 0, 1, … of the given types: the GPU half of a test
// that runs a GLSL formula beside its C++ twin. Owns its Vulkan objects; one
// thread at a time.
class ComputeShader {
 public:
  ComputeShader(const Context& ctx, std::string_view name, std::vector<vk::DescriptorType> bindings)
      : ctx_(ctx), types_(std::move(bindings)) {
    auto spirv = compile_shader(name, ShaderStage::compute);
    if (auto* e = std::get_if<RenderError>(&spirv)) {
      error_ = e->message;
      return;
    }
    const auto& code = std::get<std::vector<std::uint32_t>>(spirv);
    const auto& dev = ctx.device();
    std::vector<vk::DescriptorSetLayoutBinding> layout_bindings;
    std::vector<vk::DescriptorPoolSize> sizes;
    for (std::uint32_t b = 0; b < types_.size(); ++b) {
      layout_bindings.push_back({b, types_[b], 1, vk::ShaderStageFlagBits::eCompute});
      sizes.push_back({types_[b], 1});
    }
    layout_ = vk::raii::DescriptorSetLayout(
        dev, {.bindingCount = static_cast<std::uint32_t>(layout_bindings.size()), .pBindings = layout_bindings.data()});
    const vk::DescriptorSetLayout raw_layout = *layout_;
    pipeline_layout_ = vk::raii::PipelineLayout(dev, {.setLayoutCount = 1, .pSetLayouts = &raw_layout});
    module_ = vk::raii::ShaderModule(dev, {.codeSize = code.size() * 4, .pCode = code.data()});
    pool_ = vk::raii::DescriptorPool(dev, {.flags = vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet,
                                           .maxSets = 1,
                                           .poolSizeCount = static_cast<std::uint32_t>(sizes.size()),
                                           .pPoolSizes = sizes.data()});
    set_ = std::move(vk::raii::DescriptorSets(dev, {.descriptorPool = *pool_, .descriptorSetCount = 1,
                                                    .pSetLayouts = &raw_layout})
                         .front());
  }

  // The compile failure; empty when the shader compiled.
  [[nodiscard]] const std::string& error() const { return error_; }

  // Runs `invocations` (rounded up to whole groups) on `buffers`, one per
  // binding, with the given specialization, and waits until the host can
  // read what the shader wrote.
  void run(const std::vector<const Buffer*>& buffers, std::size_t invocations,
           const vk::SpecializationInfo* spec = nullptr) const {
    const auto& dev = ctx_.device();
    const vk::raii::Pipeline pipeline(
        dev, nullptr,
        vk::ComputePipelineCreateInfo{.stage = {.stage = vk::ShaderStageFlagBits::eCompute,
                                                .module = *module_,
                                                .pName = "main",
                                                .pSpecializationInfo = spec},
                                      .layout = *pipeline_layout_});
    std::vector<vk::DescriptorBufferInfo> infos;
    for (const Buffer* b : buffers) infos.push_back({*b->buffer, 0, VK_WHOLE_SIZE});
    std::vector<vk::WriteDescriptorSet> writes;
    for (std::uint32_t b = 0; b < infos.size(); ++b)
      writes.push_back({.dstSet = *set_, .dstBinding = b, .descriptorCount = 1, .descriptorType = types_[b],
                        .pBufferInfo = &infos[b]});
    dev.updateDescriptorSets(writes, {});
    ctx_.submit_and_wait([&](const vk::raii::CommandBuffer& cb) {
      cb.bindPipeline(vk::PipelineBindPoint::eCompute, *pipeline);
      cb.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *pipeline_layout_, 0, *set_, {});
      cb.dispatch(static_cast<std::uint32_t>((invocations + 63) / 64), 1, 1);
      const vk::MemoryBarrier to_host{.srcAccessMask = vk::AccessFlagBits::eShaderWrite,
                                      .dstAccessMask = vk::AccessFlagBits::eHostRead};
      cb.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader, vk::PipelineStageFlagBits::eHost, {}, to_host,
                         {}, {});
    });
  }

 private:
  const Context& ctx_;
  std::vector<vk::DescriptorType> types_;
  std::string error_;
  vk::raii::DescriptorSetLayout layout_{nullptr};
  vk::raii::PipelineLayout pipeline_layout_{nullptr};
  vk::raii::ShaderModule module_{nullptr};
  vk::raii::DescriptorPool pool_{nullptr};
  vk::raii::DescriptorSet set_{nullptr};  // after pool_: freed before it
};

constexpr auto kStorage = vk::DescriptorType::eStorageBuffer;
constexpr auto kUniform = vk::DescriptorType::eUniformBuffer;

std::string text(const glm::dvec4& v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "(%.9g, %.9g, %.9g, %.9g)", v.x, v.y, v.z, v.w);
  return buf;
}

std::string short_text(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

}  // namespace

TEST_F(VulkanTest, ShaderFormulasMatchCpp) {
  // Runs curved.glsl's log map, back-hemisphere map and clip positions (tourist
  // and native, front and back) in a compute shader on the same points the
  // C++ twins see, and compares.
  const ComputeShader shader(ctx(), "formulas.comp", {kStorage, kStorage, kUniform});
  ASSERT_EQ(shader.error(), "");

  int compared = 0;
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    const geometry::Space space{kind, 0.85};
    // Points at many distances and directions, including near the viewer and
    // (S3) near the antipode.
    std::vector<geometry::Point> pts;
    const double max_t = kind == SpaceKind::S3 ? std::numbers::pi - 1e-3 : 6.0;
    for (double t : {1e-5, 1e-3, 0.05, 0.3, 1.0, 1.6, 2.5, 3.1, 4.5, 6.0}) {
      if (t > max_t) continue;
      for (int j = 0; j < 6; ++j) {
        const geometry::Vec3 dir = glm::normalize(geometry::Vec3(std::sin(1.3 * j + t), 0.4 * std::cos(2.1 * j) - 0.2, -1.0 + 0.3 * j));
        pts.push_back(geometry::exp_origin(space, dir * (t * space.radius_m)));
      }
    }
    if (kind == SpaceKind::S3) pts.push_back(geometry::exp_origin(space, geometry::Vec3(0.2, 0.1, -1.0) * (0.999 * std::numbers::pi * space.radius_m / glm::length(geometry::Vec3(0.2, 0.1, -1.0)))));
    EyeOffset eye;
    eye.position_m = {0.0315, 0.0, 0.0};
    eye.fov = {-0.9, 0.7, 0.6, -0.75};
    const ViewConstants native = make_view_constants(space, ViewSettings::preset(ViewPreset::native), Isometry::identity(), eye);
    ViewConstants tourist = make_view_constants(space, ViewSettings::preset(ViewPreset::tourist), Isometry::identity(), eye);
    // One projection matrix per dispatch: the GLSL uses `proj` for every
    // variant, so give both views the same matrix for comparison.
    tourist.proj_front = native.proj_front;
    tourist.proj_back = native.proj_front;
    ViewConstants native_same = native;
    native_same.proj_back = native.proj_front;

    const std::size_t n = pts.size();
    Buffer in = Buffer::create(ctx(), n * 16, vk::BufferUsageFlagBits::eStorageBuffer);
    Buffer out = Buffer::create(ctx(), n * 6 * 16, vk::BufferUsageFlagBits::eStorageBuffer);
    Buffer params = Buffer::create(ctx(), 256, vk::BufferUsageFlagBits::eUniformBuffer);
    std::vector<glm::vec4> fin;
    for (const auto& p : pts) fin.emplace_back(p);
    in.write(fin.data(), n * 16);
    struct {
      glm::mat4 proj;
      glm::mat4 eye_from_nose;
      glm::vec4 rho_k_count;
    } block{glm::mat4(native.proj_front), glm::mat4(native.eye_from_nose),
            glm::vec4(float(space.radius_m), float(space.k()), float(n), 0.0f)};
    params.write(&block, sizeof(block));
    shader.run({&in, &out, &params}, n);
    const auto* gpu = static_cast<const glm::vec4*>(out.mapped);
    auto check = [&](const glm::dvec4& cpu, const glm::vec4& g, const char* what, std::size_t i) {
      // float32 against double: relative 2e-5 of the vector's size.
      const double scale = std::max(1.0, glm::length(cpu));
      for (int c = 0; c < 4; ++c)
        EXPECT_NEAR(double(g[c]), cpu[c], 2e-5 * scale)
            << geometry::to_string(kind) << " " << what << " point " << i << " component " << c;
      ++compared;
    };
    for (std::size_t i = 0; i < n; ++i) {
      const geometry::Point& p = glm::dvec4(fin[i]);  // the float inputs the GPU saw
      check(glm::dvec4(geometry::log_origin(space, p), geometry::distance_from_origin_rad(space, p)), gpu[6 * i + 0], "log", i);
      if (kind == SpaceKind::S3) check(glm::dvec4(geometry::back_log_origin(space, p), 0.0), gpu[6 * i + 1], "back log", i);
      check(clip_position(tourist, Hemisphere::front, p), gpu[6 * i + 2], "tourist clip", i);
      check(clip_position(tourist, Hemisphere::back, p), gpu[6 * i + 3], "tourist back clip", i);
      check(clip_position(native_same, Hemisphere::front, p), gpu[6 * i + 4], "native clip", i);
      if (kind == SpaceKind::S3) check(clip_position(native_same, Hemisphere::back, p), gpu[6 * i + 5], "native back clip", i);
    }
  }
  EXPECT_GT(compared, 500);
}

TEST_F(VulkanTest, TubeShaderMatchesCpp) {
  // Runs tube.vert's vertex computation (tube_vertex in tube.glsl, which
  // tube.vert calls) in a compute shader, specialised as the renderer
  // specialises tube.vert, on the cue stick's ribbon vertices — straight and
  // bowed, two radii, every row (both sides, the rows past the ends) — under
  // model-views that turn, roll and place the stick ahead of and behind the
  // viewer, in S3, E3 and H3, tourist and native, front and (S3) back
  // hemisphere, for targets of several sizes; and compares the clip positions
  // with its C++ twin's, tube_clip_position, on the same float inputs.
  const ComputeShader shader(ctx(), "tube_formulas.comp", {kUniform, kStorage, kStorage});
  ASSERT_EQ(shader.error(), "");
  struct TubeInput {  // tube_formulas.comp's, std430
    glm::mat4 model_view;
    glm::vec4 axis, tangent, up, side, place;
  };
  static_assert(sizeof(TubeInput) == 144);
  struct ViewBlock {  // tube.vert's View block, std140
    glm::mat4 proj_front, proj_back, eye_from_nose;
    glm::vec4 params;
  };
  struct Spec {
    std::int32_t native_view, curvature, back;
  };
  const vk::SpecializationMapEntry spec_entries[] = {
      {0, offsetof(Spec, native_view), 4}, {1, offsetof(Spec, curvature), 4}, {2, offsetof(Spec, back), 4}};
  // float32 against double, relative to the clip vector's length. float's
  // 6e-8 grows: each vertex's offsets are differences of projected points a
  // tube radius (6–12 mm) apart, taken in pixels of targets up to 1920 wide,
  // and the native map and S3 normalisation add their own rounding
  // (measured on lavapipe: 1.3e-6, 7e-4 px). 1e-5 moves a vertex inside the
  // view by at most 0.02 px on these targets, below the 0.03 px that
  // TheStickFollowsSubMillimetreBends asks of the image; a wrong sign or term
  // in either twin moves vertices by more (a margin 0.05 px off fails every
  // drawn vertex).
  constexpr double kRelativeTolerance = 1e-5;

  EyeOffset eye;
  eye.position_m = {0.0315, 0.0, 0.0};
  eye.fov = {-0.9, 0.7, 0.6, -0.75};
  const std::array<glm::dvec2, 3> targets{glm::dvec2(256.0, 256.0), glm::dvec2(1024.0, 768.0),
                                          glm::dvec2(1920.0, 1080.0)};
  int compared = 0, drawn = 0, failed = 0, dispatches = 0;
  double worst = 0.0, worst_px = 0.0;
  std::string worst_case;
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    // The radius as the GPU gets it (a float), so both twins use one value.
    const double rho = double(float(kind == SpaceKind::S3 ? 0.573 : kind == SpaceKind::H3 ? 0.848 : 1.0));
    const geometry::Space space{kind, rho};
    using geometry::Vec3;
    // Stick (model) → viewer: ahead (as the stimulus scenes place it; turned
    // and rolled; beyond the S3 equator ρπ/2 = 0.9 m) and behind (what the
    // S3 back hemisphere shows; elsewhere tube.vert puts them beyond the far
    // plane).
    const std::array<Isometry, 5> poses{
        geometry::translation_m(space, Vec3(0.0, -0.25, -0.75)),
        geometry::translation_m(space, Vec3(-0.2, 0.1, -0.6)) * geometry::rotation(Vec3(0.0, 1.0, 0.0), 0.5) *
            geometry::rotation(Vec3(1.0, 0.0, 0.0), 1.1),
        geometry::translation_m(space, Vec3(0.15, -0.3, -1.1)) * geometry::rotation(Vec3(0.0, 0.0, 1.0), 0.3) *
            geometry::rotation(Vec3(1.0, 0.0, 0.0), -0.6),
        geometry::translation_m(space, Vec3(0.1, -0.2, 0.8)) * geometry::rotation(Vec3(0.0, 1.0, 0.0), 2.8),
        geometry::translation_m(space, Vec3(-0.3, 0.2, 0.7)) *
            geometry::rotation(glm::normalize(Vec3(1.0, 1.0, 0.0)), 2.0)};
    const std::array<geometry::BentStick, 2> sticks{geometry::BentStick{1.0, 0.0, 0.0125},
                                                    geometry::BentStick{0.8, 0.03, 0.006}};
    std::vector<TubeInput> inputs;
    std::vector<std::size_t> pose_of;
    for (std::size_t p = 0; p < poses.size(); ++p)
      for (const geometry::BentStick& stick : sticks)
        for (const TubeVertex& v : build_stick(space, stick, 0, StickMarks::rings).tube_vertices) {
          inputs.push_back({glm::mat4(poses[p].m), v.axis, v.tangent, v.up, v.side, v.place});
          pose_of.push_back(p);
        }
    const std::size_t n = inputs.size();
    Buffer view_buffer = Buffer::create(ctx(), 256, vk::BufferUsageFlagBits::eUniformBuffer);
    Buffer in = Buffer::create(ctx(), n * sizeof(TubeInput), vk::BufferUsageFlagBits::eStorageBuffer);
    Buffer out = Buffer::create(ctx(), n * 16, vk::BufferUsageFlagBits::eStorageBuffer);
    in.write(inputs.data(), n * sizeof(TubeInput));

    for (const ViewPreset preset : {ViewPreset::tourist, ViewPreset::native})
      for (const Hemisphere hemi : {Hemisphere::front, Hemisphere::back}) {
        if (hemi == Hemisphere::back && kind != SpaceKind::S3) continue;
        ViewConstants vc = make_view_constants(space, ViewSettings::preset(preset), Isometry::identity(), eye);
        // The matrices as the GPU gets them (floats).
        vc.proj_front = glm::dmat4(glm::mat4(vc.proj_front));
        vc.proj_back = glm::dmat4(glm::mat4(vc.proj_back));
        vc.eye_from_nose = glm::dmat4(glm::mat4(vc.eye_from_nose));
        const glm::dvec2 size = targets[static_cast<std::size_t>(dispatches++) % targets.size()];
        const ViewBlock block{glm::mat4(vc.proj_front), glm::mat4(vc.proj_back), glm::mat4(vc.eye_from_nose),
                              glm::vec4(float(rho), float(size.x), float(size.y), 0.0f)};
        view_buffer.write(&block, sizeof(block));
        const Spec spec{vc.projection == Projection::native ? 1 : 0, static_cast<std::int32_t>(space.k()),
                        hemi == Hemisphere::back ? 1 : 0};
        const vk::SpecializationInfo spec_info{
            .mapEntryCount = 3, .pMapEntries = spec_entries, .dataSize = sizeof(spec), .pData = &spec};
        shader.run({&view_buffer, &in, &out}, n, &spec_info);
        const auto* gpu = static_cast<const glm::vec4*>(out.mapped);
        for (std::size_t i = 0; i < n; ++i) {
          const TubeInput& x = inputs[i];
          const TubeVertex v{x.axis, x.tangent, x.up, x.side, glm::vec4(0.0f), x.place};
          const glm::dvec4 cpu = tube_clip_position(vc, hemi, glm::dmat4(x.model_view), v, size.x, size.y);
          const glm::dvec4 g(gpu[i]);
          double error = 0.0;
          for (int c = 0; c < 4; ++c) error = std::max(error, std::abs(g[c] - cpu[c]) / glm::length(cpu));
          if (std::isnan(error)) error = std::numeric_limits<double>::infinity();
          ++compared;
          if (cpu != glm::dvec4(0.0, 0.0, 2.0, 1.0)) {
            ++drawn;
            const glm::dvec2 px = (glm::dvec2(g) / g.w - glm::dvec2(cpu) / cpu.w) * size / 2.0;
            worst_px = std::max({worst_px, std::abs(px.x), std::abs(px.y)});
          }
          if (error > kRelativeTolerance) ++failed;
          if (error > worst) {
            worst = error;
            worst_case = std::string(geometry::to_string(kind)) + " " + std::string(to_string(vc.projection)) +
                         (hemi == Hemisphere::back ? " back" : " front") + ", pose " + std::to_string(pose_of[i]) +
                         ", input " + std::to_string(i) + ": C++ " + text(cpu) + ", GLSL " + text(g);
          }
        }
      }
  }
  // What was measured, also in the test's XML output (--gtest_output=xml).
  RecordProperty("max_relative_error", short_text(worst));
  RecordProperty("max_error_px", short_text(worst_px));
  EXPECT_EQ(failed, 0) << failed << " of " << compared << " clip positions differ by more than "
                       << short_text(kRelativeTolerance) << " of their length; the largest, " << short_text(worst)
                       << ", at " << worst_case << "; the largest on screen: " << short_text(worst_px) << " px";
  EXPECT_GT(compared, 5000);
  EXPECT_GT(drawn, 5000);  // not only the placeholder of vertices behind the eye
}

// ---- fidelity: anti-aliasing and colour ----------------------------------

namespace {

// Linear RGB of a pixel of an sRGB-encoded image.
glm::dvec3 linear_at(const Rgba8Image& img, int x, int y) {
  const std::size_t i = 4 * (static_cast<std::size_t>(y) * img.width + x);
  return {srgb_to_linear(img.pixels[i] / 255.0f), srgb_to_linear(img.pixels[i + 1] / 255.0f),
          srgb_to_linear(img.pixels[i + 2] / 255.0f)};
}

// Mean absolute difference (linear light, 0–1) of `img` from `reference`
// downsampled by box-filtering factor² pixels in linear light — what an
// ideal anti-aliased image of the same scene holds.
double difference_from_supersampled(const Rgba8Image& img, const Rgba8Image& reference, int factor, int first_row) {
  double sum = 0.0;
  for (int y = first_row; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      glm::dvec3 box(0.0);
      for (int j = 0; j < factor; ++j)
        for (int i = 0; i < factor; ++i) box += linear_at(reference, factor * x + i, factor * y + j);
      const glm::dvec3 d = glm::abs(linear_at(img, x, y) - box / double(factor * factor));
      sum += (d.x + d.y + d.z) / 3.0;
    }
  return sum / (img.width * (img.height - first_row));
}

Rgba8Image render_left(const Context& ctx, const StimulusScene& s, std::uint32_t px, std::uint32_t msaa) {
  Renderer renderer(ctx, RendererOptions{.msaa = msaa});
  OffscreenTarget target(ctx, px, px);
  renderer.render(s.scene, frame_for(s, ViewPreset::tourist, px), target);
  return target.image(Eye::left);
}

}  // namespace

TEST_F(VulkanTest, MultisamplingIsClampedToTheDevice) {
  for (const std::uint32_t n : {1u, 2u, 4u, 8u}) {
    const std::uint32_t used = supported_msaa(ctx(), n);
    EXPECT_LE(used, n);
    EXPECT_EQ(Renderer(ctx(), RendererOptions{.msaa = n}).msaa(), used);
  }
  EXPECT_EQ(supported_msaa(ctx(), 1), 1u);
  EXPECT_EQ(supported_msaa(ctx(), 4), 4u);  // every Vulkan device supports 4 (spec, "Required Limits")
}

// "auto" (no count asked) draws a CPU device such as lavapipe with one sample,
// where multisampling costs per sample and per pixel.
TEST_F(VulkanTest, AutomaticMultisamplingIsOneSampleOnACpuDevice) {
  ASSERT_TRUE(ctx().is_software());
  EXPECT_EQ(automatic_msaa(ctx()), 1u);
  EXPECT_EQ(Renderer(ctx(), RendererOptions{.msaa = std::nullopt}).msaa(), 1u);
  EXPECT_EQ(Renderer(ctx(), RendererOptions{}).msaa(), 4u);  // the renderer's own default stays 4
}

TEST_F(VulkanTest, MultisampledEdgesApproachASupersampledImage) {
  // The table at 128² (the image's lower half: the prompt panel above is
  // text, sampled from its atlas), against the same scene drawn at 512² with
  // one sample and box-filtered down: 4× MSAA must remove most of the
  // aliasing that one sample per pixel leaves on the table's edges.
  const StimulusScene s = make(SpaceKind::E3, SceneKind::table);
  const Rgba8Image reference = render_left(ctx(), s, 512, 1);
  const double aliased = difference_from_supersampled(render_left(ctx(), s, 128, 1), reference, 4, 64);
  const double smoothed = difference_from_supersampled(render_left(ctx(), s, 128, 4), reference, 4, 64);
  EXPECT_GT(aliased, 0.0);
  EXPECT_LT(smoothed, 0.6 * aliased) << "msaa 1: " << aliased << ", msaa 4: " << smoothed;
}

TEST_F(VulkanTest, TheStickIsAntiAliasedWithOneSamplePerPixel) {
  // The stick's coverage is computed per pixel, so one sample per pixel
  // already matches the supersampled image as closely as four do, and both
  // far more closely than the table's sampled edges at one sample.
  const StimulusScene s = make(SpaceKind::E3, SceneKind::stick);
  const Rgba8Image reference = render_left(ctx(), s, 512, 1);
  const double one = difference_from_supersampled(render_left(ctx(), s, 128, 1), reference, 4, 64);
  const double four = difference_from_supersampled(render_left(ctx(), s, 128, 4), reference, 4, 64);
  EXPECT_GT(one, 0.0);
  EXPECT_LT(one, 1.15 * four) << "msaa 1: " << one << ", msaa 4: " << four;
  EXPECT_LT(four, 1.15 * one) << "msaa 1: " << one << ", msaa 4: " << four;
}

TEST_F(VulkanTest, TheStickFollowsSubMillimetreBends) {
  // The stick is bent toward the viewer in 0.5 mm steps (its middle moves
  // 0.06 px per step at 512² over 90°). The middle's height, read from the
  // left eye's pixels as the luminance centroid of the columns there, must
  // move with the pinhole projection of the centre line's middle (from the
  // head and eye isometries, not the renderer's view math) to within 0.03 px
  // at one and at four samples per pixel; edges quantized to a sample grid
  // are off by up to 0.1 px.
  constexpr std::uint32_t kPx = 512;
  const auto scene = [](double sagitta_m) { return make_from(SceneKind::stick, settings_in(SpaceKind::E3, sagitta_m)); };
  const StimulusScene straight = scene(0.0);
  const auto project_middle = [&](double sagitta_m) {
    const Isometry eye = straight.head * geometry::translation_m(straight.space, geometry::Vec3(-0.0315, 0.0, 0.0));
    const geometry::Point middle =
        geometry::translation_m(straight.space, geometry::Vec3(0.0, -0.25, -0.75)).m *
        geometry::BentStick{1.0, sagitta_m, 0.012}.centre_point(straight.space, Isometry::identity(), 0.0);
    const glm::dvec4 q = glm::inverse(eye.m) * middle;
    return glm::dvec2(kPx / 2.0 + (kPx / 2.0) * q.x / -q.z, kPx / 2.0 - (kPx / 2.0) * q.y / -q.z);
  };
  const glm::dvec2 first = project_middle(0.0);
  const auto measured_height = [&](const Rgba8Image& img) {
    double sum = 0.0, weight = 0.0;
    const double bg = linear_at(img, 5, 5).y;
    for (int x = int(first.x) - 3; x <= int(first.x) + 3; ++x)
      for (int row = int(first.y) - 15; row <= int(first.y) + 15; ++row) {
        const double w = std::max(0.0, linear_at(img, x, row).y - bg);
        sum += w * (row + 0.5);
        weight += w;
      }
    return sum / weight;
  };
  for (const std::uint32_t msaa : {1u, 4u}) {
    Renderer renderer(ctx(), RendererOptions{.msaa = msaa});
    OffscreenTarget target(ctx(), kPx, kPx);
    double worst = 0.0, start = 0.0;
    for (int i = 0; i <= 5; ++i) {
      const double sagitta = 0.0005 * i;
      const StimulusScene s = scene(sagitta);
      renderer.render(s.scene, frame_for(s, ViewPreset::tourist, kPx), target);
      const double height = measured_height(target.image(Eye::left));
      if (i == 0) start = height;
      worst = std::max(worst, std::abs((height - start) - (project_middle(sagitta).y - first.y)));
    }
    EXPECT_LT(worst, 0.03) << "msaa " << msaa;
  }
}

TEST_F(VulkanTest, SrgbTargetsShowTheAuthoredDisplayValues) {
  // Colours are authored as display values and shaded in linear light; the
  // sRGB target encodes them back, so the background's bytes are the
  // authored values × 255 (not their linear values, which would be ~0).
  const StimulusScene s = make(SpaceKind::E3, SceneKind::stick);
  Renderer renderer(ctx());
  OffscreenTarget target(ctx(), 64, 64);
  FrameDescription f = frame_for(s, ViewPreset::tourist, 64);
  f.settings.eyes = EyeSelection::left;
  renderer.render(s.scene, f, target);
  const Rgba8Image& right = target.image(Eye::right);  // background only
  EXPECT_NEAR(right.pixels[0], 0.015 * 255, 1.0);
  EXPECT_NEAR(right.pixels[1], 0.017 * 255, 1.0);
  EXPECT_NEAR(right.pixels[2], 0.03 * 255, 1.0);
}

// ---- head-locked panels: what the participant reads ----------------------

using test::find_panel;
using test::first_line_rows;
using test::PanelInk;

// The response panel is fixed to the head and drawn over the curved scene:
// its capitals are as tall as the protocol's viewing.text_height_deg says,
// at least half a degree, identical in S3, E3 and H3, and never mirrored
// (an F's stem is on its left).
TEST_F(VulkanTest, ResponsePanelTextIsTheStatedVisualAngleInEverySpace) {
  constexpr std::uint32_t px = 640;  // the desktop pilot's eye
  const double px_per_deg = px / 90.0;
  // Pixels per radian at the centre of a 90° view.
  const double focal_px = 0.5 * px / std::tan(std::numbers::pi / 4.0);
  const std::string prompt = "FFF FFF\n\n[1]\u00a0one     [2]\u00a0two";
  std::vector<PanelInk> panels;
  for (const SpaceKind kind : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    SCOPED_TRACE(std::string(geometry::to_string(kind)));
    const auto s = settings_in(kind);
    auto made = harness::runner::viewed_scene(SceneKind::table, s, {.panel_px_per_deg = px_per_deg}, prompt,
                                              CURVLAB_DEFAULT_FONT);
    ASSERT_TRUE(made) << made.error().message;
    Renderer renderer(ctx(), RendererOptions{.msaa = 1});
    OffscreenTarget target(ctx(), px, px);
    renderer.render(made.value().scene, frame_for(made.value(), ViewPreset::tourist, px), target);
    const Rgba8Image left = target.image(Eye::left);
    if (kind == SpaceKind::H3) {
      std::filesystem::create_directories(std::filesystem::path(CURVLAB_GOLDEN_OUT_DIR) / "panels");
      ASSERT_TRUE(test::png_written(
          write_png((std::filesystem::path(CURVLAB_GOLDEN_OUT_DIR) / "panels" / "response_panel_H3.png").string(), left)));
    }
    PanelInk p = find_panel(left);
    ASSERT_GT(p.width(), 20) << "no response panel in the image";
    // The panel lies above the line of sight, clear of the image's centre.
    EXPECT_LT(p.y1, static_cast<int>(px) / 2);

    const auto [top, bottom] = first_line_rows(p);
    ASSERT_GE(top, 0) << "no text on the panel";
    const int cap_px = bottom - top + 1;
    auto block = renderer::render_text_block("F", s.viewing.text_height_deg * px_per_deg, 600, CURVLAB_DEFAULT_FONT);
    ASSERT_TRUE(std::holds_alternative<renderer::TextBlock>(block));
    const double cap_deg = std::get<renderer::TextBlock>(block).cap_height_px / px_per_deg;
    // A flat card 16° above the line of sight: a degree there spans sec²(16°)
    // of a degree's pixels at the centre.
    const double sec2 = 1.0 / std::pow(std::cos(16.0 * std::numbers::pi / 180.0), 2);
    const double expected_px = cap_deg * std::numbers::pi / 180.0 * focal_px * sec2;
    EXPECT_NEAR(cap_px, expected_px, 1.5) << "capital height " << cap_px << " px, stated " << cap_deg << "°";
    EXPECT_GE(cap_px, 0.5 * std::numbers::pi / 180.0 * focal_px) << "text under half a degree";

    // Not mirrored: the first ink column of the first line is an F's stem
    // (as tall as the capital), the last its arm's end (short).
    const auto [first_col, last_col] = test::ink_columns(p, top, bottom);
    EXPECT_GE(test::column_ink(p, first_col, top, bottom), cap_px - 1);
    EXPECT_LE(test::column_ink(p, last_col, top, bottom), cap_px / 2);
    panels.push_back(std::move(p));
  }
  for (std::size_t i = 1; i < panels.size(); ++i) {
    EXPECT_EQ(panels[i].width(), panels[0].width());
    EXPECT_EQ(panels[i].height(), panels[0].height());
    EXPECT_EQ(panels[i].ink, panels[0].ink) << "the panel's text differs between spaces";
  }
}

TEST_F(VulkanTest, TextPanelsStaySharpUnderMultisampling) {
  // The fragment shader runs once per pixel, so the text inside a panel is
  // sampled exactly as without multisampling; only geometric edges change.
  const StimulusScene s = make(SpaceKind::E3, SceneKind::stick);
  const Rgba8Image one = render_left(ctx(), s, 256, 1);
  const Rgba8Image four = render_left(ctx(), s, 256, 4);
  // The response panel, its border left out.
  const PanelInk panel = find_panel(one);
  ASSERT_GT(panel.width(), 20) << "no response panel in the image";
  int ink = 0, differing = 0;
  for (int y = panel.y0 + 2; y <= panel.y1 - 2; ++y)
    for (int x = panel.x0 + 2; x <= panel.x1 - 2; ++x) {
      const std::size_t i = 4 * (static_cast<std::size_t>(y) * 256 + x);
      if (one.pixels[i] > 128) ++ink;
      for (int c = 0; c < 3; ++c)
        if (std::abs(int(one.pixels[i + c]) - int(four.pixels[i + c])) > 1) {
          ++differing;
          break;
        }
    }
  EXPECT_GT(ink, 50);  // the panel does hold text
  EXPECT_EQ(differing, 0);
}
