#include "curvlab/harness/render_result.hpp"
#include "curvlab/harness/runner/preview.hpp"

#include "curvlab/harness/data/sha256.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/runner/predict.hpp"
#include "curvlab/harness/runner/stimulus.hpp"
#include "curvlab/harness/runner/trial_state.hpp"
#include "curvlab/harness/platform/process.hpp"
#include "curvlab/harness/version.hpp"
#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/image_io.hpp"
#include "curvlab/renderer/offscreen.hpp"
#include "curvlab/renderer/renderer.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <tuple>

namespace curvlab::harness::runner {
namespace {

namespace fs = std::filesystem;
using protocol::Settings;

std::string num(double v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// Metres as millimetres, to the micrometre: 0.07 m is "70", not the
// "70.00000000000001" that 0.07 * 1000 prints in shortest form.
std::string mm(double metres) { return num(std::round(metres * 1e6) / 1e3); }

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

std::string duration_text(std::int64_t ms) {
  const std::int64_t s = (ms + 500) / 1000;
  if (s < 60) return std::to_string(s) + " s";
  return std::to_string(s / 60) + " min " + std::to_string(s % 60) + " s";
}

// Everything a trial's stimulus and timing depend on, as shown on the sheet;
// two trials with equal rows and levels show the participant the same thing.
std::vector<std::pair<std::string, std::string>> settings_rows(const Settings& s,
                                                               const protocol::Derived& d) {
  const auto yes = [](bool b) { return std::string(b ? "yes" : "no"); };
  const auto& st = s.stimulus;
  return {
      {"space", std::string(geometry::to_string(s.space.kind))},
      {"radius", fixed(d.radius_m, 4) + " m" + (s.space.radius_m ? "" : " (from the table)")},
      {"virtual table", std::to_string(d.table_sides) + " sides of " + fixed(d.side_rad, 4) + " rad"},
      {"view", std::string(renderer::to_string(s.viewing.projection)) + ", " +
                   std::string(renderer::to_string(s.viewing.eyes)) + " eye" +
                   (s.viewing.eyes == renderer::EyeSelection::both ? "s" : "")},
      {"back hemisphere", yes(s.viewing.back_hemisphere) + (s.space.kind == geometry::SpaceKind::S3 ? "" : " (drawn in S3 only)")},
      {"IPD", mm(s.viewing.ipd_m) + " mm"},
      {"tracking", std::string(geometry::to_string(s.tracking))},
      {"stick", st.show_stick ? num(st.stick_length_m) + " m long, " + mm(st.stick_radius_m) +
                                    " mm radius, sagitta " + mm(st.stick_sagitta_m) + " mm"
                              : "hidden"},
      {"stick pose", std::string(protocol::to_string(st.stick_anchor)) + " anchor, " +
                         num(st.stick_distance_m) + " m away, height " + num(st.stick_height_m) +
                         " m, yaw " + num(st.stick_yaw_deg) + "°"},
      {"table top", st.show_table ? "sagitta " + mm(st.table_sagitta_m) + " mm" : "hidden"},
      {"balls", std::to_string(st.balls) + " × " + mm(st.ball_radius_m) + " mm radius"},
      {"physical table", num(s.table.edge_m) + " m edge, " + num(s.table.height_m) + " m high"},
      {"timeline", std::to_string(s.timeline.fixation_ms) + " / " + std::to_string(s.timeline.stimulus_ms) +
                       " / " + std::to_string(s.timeline.response_ms) + " / " +
                       std::to_string(s.timeline.iti_ms) + " ms" +
                       (s.timeline.stimulus_during_response ? "" : ", stimulus hidden while answering")},
  };
}

std::string html(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string base64(const std::string& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const auto b0 = static_cast<unsigned char>(bytes[i]);
    const auto b1 = i + 1 < bytes.size() ? static_cast<unsigned char>(bytes[i + 1]) : 0u;
    const auto b2 = i + 2 < bytes.size() ? static_cast<unsigned char>(bytes[i + 2]) : 0u;
    const unsigned v = (b0 << 16) | (b1 << 8) | b2;
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? table[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? table[v & 63] : '=';
  }
  return out;
}

// A grey red/cyan anaglyph: the left eye's luminance in red, the right's in
// green and blue (grey rather than colour anaglyphs avoid retinal rivalry
// on the green cloth). Computed on the sRGB-encoded values: a quick look,
// not a stimulus.
renderer::Rgba8Image anaglyph(const renderer::Rgba8Image& left, const renderer::Rgba8Image& right) {
  renderer::Rgba8Image out{left.width, left.height, std::vector<std::uint8_t>(left.pixels.size())};
  for (std::size_t i = 0; i + 3 < left.pixels.size(); i += 4) {
    const auto luma = [](const std::vector<std::uint8_t>& p, std::size_t k) {
      return static_cast<std::uint8_t>(std::lround(0.299 * p[k] + 0.587 * p[k + 1] + 0.114 * p[k + 2]));
    };
    const auto r = luma(right.pixels, i);
    out.pixels[i] = luma(left.pixels, i);
    out.pixels[i + 1] = r;
    out.pixels[i + 2] = r;
    out.pixels[i + 3] = 255;
  }
  return out;
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

const protocol::Block* block_at(const protocol::Protocol& p, std::size_t protocol_block) {
  return protocol_block < p.blocks.size() ? &p.blocks[protocol_block] : nullptr;
}

std::string levels_text(const std::vector<std::pair<std::string, std::string>>& levels) {
  std::string out;
  for (const auto& [f, l] : levels) out += (out.empty() ? "" : ", ") + f + " = " + l;
  return out.empty() ? "(no factors)" : out;
}

struct Rendered {
  std::string left, right, anaglyph;  // file names under images/
};

// What a trial's onset shows: its planned settings with the value its
// judgement's type sets then (a staircase's start, an adjustment trial's
// drawn start), and the note that says so ("" when the type sets none).
struct Onset {
  Settings settings;
  protocol::Derived derived;
  std::string note;
};

Onset onset_of(const protocol::Protocol& p, const protocol::PlannedTrial& t) {
  Onset out{t.settings, t.derived, ""};
  const protocol::Block* block = block_at(p, t.protocol_block);
  if (!block) return out;
  const auto& j = block->judgement;
  const auto value = j.type->onset_value(j, t);
  if (!value) return out;
  protocol::set_numeric_setting(out.settings, j.parameter, value->value);
  // The loader checked every value a judgement reaches, so this derives;
  // the planned values stay where it would not.
  if (const auto derived = protocol::derive(out.settings)) out.derived = *derived;
  out.note = value->note;
  return out;
}

// What the judgement's type tells apart within a cell (a staircase).
std::vector<std::pair<std::string, std::string>> tracks_of(const protocol::Protocol& p,
                                                           const protocol::PlannedTrial& t) {
  const protocol::Block* block = block_at(p, t.protocol_block);
  if (!block) return {};
  return block->judgement.type->conditions(block->judgement, t);
}

std::string condition_title(const PreviewCondition& c) {
  std::string out = levels_text(c.levels);
  for (const auto& [name, value] : c.tracks) out += ", " + name + " \"" + value + "\"";
  return c.practice ? out + " — practice" : out;
}

constexpr const char* kStyle = R"(
body { font: 15px/1.4 "DejaVu Sans", sans-serif; margin: 24px; color: #1d1d1f; background: #fafafa; }
h1 { margin-bottom: 4px; } h2 { margin-top: 32px; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; margin: 8px 0; } td, th { border: 1px solid #ddd; padding: 3px 8px;
 text-align: left; vertical-align: top; } th { background: #eee; }
.meta td:first-child { font-weight: bold; } code { font-size: 13px; word-break: break-all; }
.conditions { display: grid; grid-template-columns: repeat(auto-fill, minmax(620px, 1fr)); gap: 16px; }
.condition { background: #fff; border: 1px solid #ccc; border-radius: 6px; padding: 12px; }
.condition h3 { margin: 0 0 8px 0; font-size: 16px; }
.pair { display: flex; gap: 6px; } .pair figure { margin: 0; flex: 1; } .pair img { width: 100%; display: block;
 border: 1px solid #999; background: #000; } figcaption { font-size: 12px; color: #555; text-align: center; }
.small { font-size: 12px; color: #555; } .text { white-space: pre-wrap; background: #fff; border: 1px solid #ddd;
 padding: 8px; margin: 4px 0; }
.bar { display: inline-block; height: 10px; background: #4a7bd0; vertical-align: middle; }
)";

}  // namespace

std::vector<PreviewCondition> preview_conditions(const protocol::Protocol& p, const protocol::Design& design) {
  std::vector<PreviewCondition> out;
  std::map<std::string, std::size_t> index;
  for (const auto& t : design.trials) {
    // A play or questionnaire block's one trial shows no stimulus to judge:
    // the block table describes it instead.
    if (p.blocks.at(t.protocol_block).kind != "trials") continue;
    // Trials are one condition when their levels, tracks and planned
    // settings agree and both are practice or both are not; an adjustment
    // trial's own start value does not make a condition of its own.
    auto tracks = tracks_of(p, t);
    std::string key = t.practice ? "practice\x1e" : "main\x1e";
    for (const auto& [f, l] : t.levels) key += f + "=" + l + "\x1f";
    key += "\x1e";
    for (const auto& [n, v] : tracks) key += n + "=" + v + "\x1f";
    key += "\x1e";
    for (const auto& [n, v] : settings_rows(t.settings, t.derived)) key += n + "=" + v + "\x1f";
    auto it = index.find(key);
    if (it == index.end()) {
      it = index.emplace(key, out.size()).first;
      const Onset onset = onset_of(p, t);
      out.push_back({.levels = t.levels,
                     .tracks = std::move(tracks),
                     .practice = t.practice,
                     .settings = settings_rows(onset.settings, onset.derived),
                     .onset_note = onset.note,
                     .first_trial = t.index,
                     .trials_per_block = {}});
    }
    auto& per_block = out[it->second].trials_per_block;
    const auto found = std::find_if(per_block.begin(), per_block.end(),
                                    [&](const auto& e) { return e.first == t.block; });
    if (found == per_block.end()) per_block.emplace_back(t.block, 1);
    else ++found->second;
  }
  // Block by block in run order, each in factorial order (the last factor
  // varying fastest) and its staircases in file order, rather than in the
  // shuffled order of the trials.
  const auto order = [&](const PreviewCondition& c) {
    const auto& t = design.trials[c.first_trial];
    return std::tuple{t.block_position, t.cell, t.staircase ? t.staircase->index : 0};
  };
  std::stable_sort(out.begin(), out.end(),
                   [&](const PreviewCondition& a, const PreviewCondition& b) { return order(a) < order(b); });
  return out;
}

namespace {

// The sheet's image size per eye: the request's, else the protocol's scaled
// down to at most 480 px wide.
std::pair<std::uint32_t, std::uint32_t> sheet_size(const protocol::Protocol& p, const PreviewRequest& rq) {
  if (rq.size) return *rq.size;
  auto w = static_cast<std::uint32_t>(p.resolution_width);
  auto h = static_cast<std::uint32_t>(p.resolution_height);
  if (w > 480) {
    h = std::max<std::uint32_t>(16, static_cast<std::uint32_t>(std::lround(480.0 * h / w)));
    w = 480;
  }
  return {w, h};
}

struct SheetRenderer {
  renderer::Renderer& r;
  renderer::OffscreenTarget& target;
  std::uint32_t w, h;
  fs::path dir;
};

// One condition's onset stereo pair and anaglyph, written under images/.
Result<Rendered> render_condition(const protocol::Protocol& p, const protocol::PlannedTrial& t, std::size_t k,
                                  SheetRenderer& out_to) {
  const Settings s = onset_of(p, t).settings;
  Rendered out;
  const protocol::Block* block = block_at(p, t.protocol_block);
  auto made = make_world(s);
  if (!made) return made.error();
  const World world = std::move(made).value();
  auto built = TrialScene::build(world, s, block ? response_panel_text(block->judgement, {}) : std::string(),
                                 CURVLAB_DEFAULT_FONT);
  if (!built) return built.error();
  auto& scene = built.value();
  const geometry::Isometry head = standing_head(world, s);
  scene.place(place_stimulus(world, s, head), head);
  scene.show(Phase::stimulus, s.timeline.stimulus_during_response);
  renderer::FrameDescription desc;
  desc.space = world.space;
  desc.settings = view_settings(s, renderer::Eye::right);
  desc.head = head;
  desc.rig = renderer::StereoRig::from_ipd(
      s.viewing.ipd_m, renderer::Fov::symmetric(std::numbers::pi / 2.0, double(out_to.w) / double(out_to.h)));
  desc.width_px = out_to.w;
  desc.height_px = out_to.h;
  (void)out_to.r.render(scene.scene(), desc, out_to.target);
  const std::string stem = "condition_" + std::to_string(k + 1);
  out.left = stem + "_left.png";
  out.right = stem + "_right.png";
  out.anaglyph = stem + "_anaglyph.png";
  const auto& left = out_to.target.image(renderer::Eye::left);
  const auto& right = out_to.target.image(renderer::Eye::right);
  const fs::path images = out_to.dir / "images";
  for (const auto& [name, image] : {std::pair{out.left, &left}, std::pair{out.right, &right}})
    if (auto written = from_renderer(renderer::write_png((images / name).string(), *image)); !written)
      return written.error();
  if (auto written = from_renderer(renderer::write_png((images / out.anaglyph).string(), anaglyph(left, right)));
      !written)
    return written.error();
  return out;
}

void write_header(std::ostringstream& o, const protocol::Protocol& p, const PreviewRequest& rq,
                  const protocol::Design& design, std::size_t conditions, const std::string& device,
                  std::uint32_t w, std::uint32_t h, std::uint32_t msaa) {
  o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>"
    << html(p.meta.name + " " + p.meta.version) << " — curvlab preview</title>\n<style>" << kStyle
    << "</style>\n</head>\n<body>\n";
  o << "<h1>" << html(p.meta.name) << " <span class=\"small\">" << html(p.meta.version) << "</span></h1>\n";
  if (!p.meta.description.empty()) o << "<p>" << html(p.meta.description) << "</p>\n";
  o << "<table class=\"meta\">\n"
    << "<tr><td>protocol file</td><td><code>" << html(fs::path(rq.protocol_path).filename().string())
    << "</code></td></tr>\n"
    << "<tr><td>protocol SHA-256</td><td><code id=\"sha256\">" << curvlab::harness::data::sha256_hex(rq.protocol_text)
    << "</code></td></tr>\n"
    << "<tr><td>software</td><td>curvlab " << html(std::string(software_version())) << " ("
    << html(std::string(git_commit())) << ")</td></tr>\n"
    << "<tr><td>renderer</td><td>" << html(device) << ", " << w << "×" << h
    << " px per eye, 90° horizontal field of view, " << msaa << " samples per pixel</td></tr>\n"
    << "<tr><td>participant</td><td>" << design.participant << " (seed " << design.seed;
  if (design.counterbalance_row) o << ", counterbalance row " << *design.counterbalance_row + 1;
  o << ")</td></tr>\n"
    << "<tr><td>trials</td><td>" << design.trials.size() << " in " << design.blocks.size() << " blocks, "
    << conditions << " distinct conditions</td></tr>\n"
    << "<tr><td>estimated duration</td><td>" << duration_text(design.estimated_duration_ms())
    << " (timelines and minimum breaks; reading instructions not included)</td></tr>\n</table>\n";
}

// Block order and timelines.
// What a play or questionnaire block does, in the judgement's column.
std::string kind_text(const protocol::Block& b) {
  if (b.kind == "play") {
    std::string out = "play: billiards until " + duration_text(static_cast<std::int64_t>(b.play.duration_s * 1000.0));
    if (b.play.shots > 0) out += ", " + std::to_string(b.play.shots) + " shots";
    if (b.play.until_all_pocketed) out += " or every ball pocketed";
    return out + " (rack of " + std::to_string(b.play.rack) + ")";
  }
  if (b.kind == "questionnaire")
    return "questionnaire: " + (b.instrument.title.empty() ? b.instrument.name : b.instrument.title) + " (" +
           std::to_string(b.instrument.items.size()) + " items)";
  return b.kind;
}

void write_blocks(std::ostringstream& o, const protocol::Protocol& p, const protocol::Design& design) {
  o << "<h2>Block order for participant " << design.participant << "</h2>\n<table>\n"
    << "<tr><th>#</th><th>block</th><th>trials</th><th>judgement</th><th>timeline (fixation / stimulus / "
       "response / ITI)</th><th>breaks</th></tr>\n";
  for (std::size_t i = 0; i < design.blocks.size(); ++i) {
    const auto& pb = design.blocks[i];
    const protocol::Block* b = block_at(p, pb.protocol_block);
    std::string timeline = "—";
    if (pb.trial_count > 0) {
      const auto& tl = design.trials[pb.first_trial].settings.timeline;
      timeline = std::to_string(tl.fixation_ms) + " / " + std::to_string(tl.stimulus_ms) + " / " +
                 std::to_string(tl.response_ms) + " / " + std::to_string(tl.iti_ms) + " ms (" +
                 num(static_cast<double>(tl.total_ms()) / 1000.0) + " s per trial at most)";
    }
    std::string judgement = b ? std::string(b->judgement.type->name()) : "";
    if (b && b->judgement.type->stops_early()) judgement += " (trial count at most)";
    if (b && b->kind != "trials") {
      judgement = kind_text(*b);
      timeline = "—";
    }
    std::string breaks = "none";
    if (b && b->break_every_trials > 0)
      breaks = "every " + std::to_string(b->break_every_trials) + " trials, at least " + duration_text(b->break_min_ms);
    o << "<tr><td>" << i + 1 << "</td><td>" << html(pb.name) << (pb.practice ? " (practice)" : "") << "</td><td>"
      << pb.trial_count << "</td><td>" << html(judgement) << "</td><td>" << timeline << "</td><td>"
      << html(breaks) << "</td></tr>\n";
  }
  o << "</table>\n";
}

// Texts the participant reads, in the order they appear.
void write_texts(std::ostringstream& o, const protocol::Protocol& p, const protocol::Design& design) {
  const auto texts = [](const std::vector<std::string>& pages) {
    std::string out;
    for (const auto& t : pages) out += "<div class=\"text\">" + html(t) + "</div>";
    return out.empty() ? std::string("—") : out;
  };
  o << "<h2>Instructions, prompts and break texts</h2>\n<table>\n<tr><th>when</th><th>text</th></tr>\n";
  if (!p.instructions_start.empty())
    o << "<tr><td>before the first block</td><td>" << texts(p.instructions_start) << "</td></tr>\n";
  for (const auto& pb : design.blocks) {
    const protocol::Block* b = block_at(p, pb.protocol_block);
    if (!pb.instructions.empty())
      o << "<tr><td>before block " << html(pb.name) << "</td><td>" << texts(pb.instructions) << "</td></tr>\n";
    if (b && b->kind == "trials" && !b->judgement.prompt.empty())
      o << "<tr><td>prompt in block " << html(pb.name) << "</td><td>" << texts({b->judgement.prompt})
        << "</td></tr>\n";
    if (b && b->break_every_trials > 0)
      o << "<tr><td>break in block " << html(pb.name) << "</td><td>" << texts({b->break_text}) << "</td></tr>\n";
  }
  if (!p.instructions_end.empty())
    o << "<tr><td>after the last block</td><td>" << texts(p.instructions_end) << "</td></tr>\n";
  o << "</table>\n";
}

std::string names_text(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out.empty() ? "—" : out;
}

// One judgement's answers with the keys and buttons that give them, then
// its type, parameter and own settings (each staircase's start, steps and
// rules; an adjustment's start range and steps).
std::string judgement_tables(const protocol::Judgement& j) {
  std::string out = "<table class=\"responses\">\n<tr><th>answer</th><th>label</th><th>keys</th>"
                    "<th>buttons</th></tr>\n";
  for (const auto& a : j.type->answer_bindings(j)) {
    const auto option = std::find_if(j.options.begin(), j.options.end(),
                                     [&](const protocol::ResponseOption& o) { return o.value == a.answer; });
    out += "<tr><td>" + html(a.answer) + "</td><td>" + html(option == j.options.end() ? "—" : option->label) +
           "</td><td>" + html(names_text(a.keys)) + "</td><td>" + html(names_text(a.buttons)) + "</td></tr>\n";
  }
  out += "</table>\n<table class=\"judgement\">\n<tr><th>judgement</th><td>" +
         html(std::string(j.type->name()) + " (" + std::string(j.type->summary()) + ")") + "</td></tr>\n";
  if (!j.parameter.empty()) out += "<tr><th>parameter</th><td>" + html(j.parameter) + "</td></tr>\n";
  for (const auto& [label, text] : j.type->settings_summary(j))
    out += "<tr><th>" + html(label) + "</th><td>" + html(text) + "</td></tr>\n";
  return out + "</table>\n";
}

// Every judgement of the session in run order, once: blocks that answer
// the same way with the same settings share one entry.
void write_responses(std::ostringstream& o, const protocol::Protocol& p, const protocol::Design& design) {
  std::vector<std::pair<std::vector<std::string>, std::string>> entries;  // blocks, tables
  for (const auto& pb : design.blocks) {
    const protocol::Block* b = block_at(p, pb.protocol_block);
    if (!b || b->kind != "trials") continue;
    const std::string tables = judgement_tables(b->judgement);
    const std::string name = pb.name + (pb.practice ? " (practice)" : "");
    const auto same = std::find_if(entries.begin(), entries.end(), [&](const auto& e) { return e.second == tables; });
    if (same == entries.end()) entries.push_back({{name}, tables});
    else same->first.push_back(name);
  }
  o << "<h2>Responses and judgement settings</h2>\n";
  for (const auto& [blocks, tables] : entries)
    o << "<h3>" << (blocks.size() == 1 ? "Block " : "Blocks ") << html(names_text(blocks)) << "</h3>\n" << tables;
}

// The predictions for a condition's levels and judged object; false when none.
bool write_predictions(std::ostringstream& o, const Prediction& prediction, const PreviewCondition& c,
                       const protocol::PlannedTrial& t) {
  bool any = false;
  const std::string judged_name(judged_kind(t.settings).name());
  const bool proportions = t.judgement->forecast() == protocol::Forecast::proportions;
  for (const auto& pc : prediction.conditions) {
    if (!proportions || pc.levels != c.levels || pc.judged != judged_name) continue;
    o << "<p class=\"small\">Predicted responses (perceived " << judged_name << " sagitta "
      << fixed(pc.perceived_m * 1000.0, 2) << " mm):</p>\n<table>\n";
    for (std::size_t i = 0; i < pc.options.size() && i < pc.proportions.size(); ++i)
      o << "<tr><td>" << html(pc.options[i]) << "</td><td>" << fixed(pc.proportions[i], 3)
        << "</td><td><span class=\"bar\" style=\"width:" << std::lround(pc.proportions[i] * 200.0)
        << "px\"></span></td></tr>\n";
    o << "</table>\n";
    any = true;
    break;
  }
  std::string rows;
  for (const auto& sp : prediction.staircases) {
    if (sp.levels != c.levels) continue;
    if (std::none_of(c.trials_per_block.begin(), c.trials_per_block.end(),
                     [&](const auto& e) { return e.first == sp.block; }))
      continue;
    // A staircase's panel shows its own convergence only.
    if (!c.tracks.empty() &&
        std::none_of(c.tracks.begin(), c.tracks.end(), [&](const auto& e) { return e.second == sp.staircase; }))
      continue;
    rows += "<tr><td>" + html(sp.staircase) + " (" + html(sp.rule) + ", " + fixed(sp.target_p * 100.0, 1) + " % " +
            html(sp.positive) + ")</td><td>" +
            (sp.target_value ? html(sp.parameter) + " = " + fixed(*sp.target_value, 4)
                             : "outside [" + num(sp.min) + ", " + num(sp.max) + "]") +
            "</td></tr>\n";
  }
  if (!rows.empty()) {
    o << "<p class=\"small\">Predicted staircase convergence (mean observer):</p>\n<table>\n" << rows << "</table>\n";
    any = true;
  }
  return any;
}

// One panel: the images, the settings, trials per block, the predictions.
void write_panel(std::ostringstream& o, std::size_t k, const PreviewCondition& c, const Rendered& img,
                 const protocol::PlannedTrial& t, const std::optional<Prediction>& prediction,
                 const std::string& prediction_note, const fs::path& dir) {
  o << "<section class=\"condition" << (c.practice ? " practice" : "") << "\" id=\"condition-" << k + 1
    << "\">\n<h3>" << k + 1 << ". " << html(condition_title(c)) << "</h3>\n<div class=\"pair\">\n";
  for (const auto& [file, caption] : {std::pair{img.left, "left eye"}, std::pair{img.right, "right eye"},
                                      std::pair{img.anaglyph, "anaglyph (red left, cyan right)"}})
    o << "<figure><img alt=\"" << caption << "\" src=\"data:image/png;base64,"
      << base64(read_bytes((dir / "images" / file).string())) << "\"><figcaption>" << caption
      << "</figcaption></figure>\n";
  o << "</div>\n";
  if (!c.onset_note.empty()) o << "<p class=\"small\">Rendered with the " << html(c.onset_note) << ".</p>\n";
  o << "<table>\n";
  for (const auto& [name, value] : c.settings)
    o << "<tr><th>" << html(name) << "</th><td>" << html(value) << "</td></tr>\n";
  o << "<tr><th>trials per block</th><td>";
  for (std::size_t i = 0; i < c.trials_per_block.size(); ++i)
    o << (i ? ", " : "") << html(c.trials_per_block[i].first) << ": " << c.trials_per_block[i].second;
  o << "</td></tr>\n</table>\n";
  if (c.practice || !prediction || !write_predictions(o, *prediction, c, t)) {
    std::string why = "no prediction: ";
    if (c.practice) why += "practice trials are not predicted";
    else if (t.judgement->forecast() == protocol::Forecast::none) why += std::string(t.judgement->name()) + " is not predicted";
    else why += prediction_note.empty() ? "none for this condition" : prediction_note;
    o << "<p class=\"small\">" << html(why) << "</p>\n";
  }
  o << "</section>\n";
}

// index.html appears whole or not at all.
Result<std::string> write_atomically(const fs::path& dir, const std::string& text) {
  const fs::path index = dir / "index.html";
  const fs::path partial = dir / "index.html.partial";
  {
    std::ofstream f(partial, std::ios::binary | std::ios::trunc);
    f << text;
    f.close();
    if (!f) return Error{Error::Kind::io, "cannot write " + partial.string()};
  }
  std::error_code ec;
  fs::rename(partial, index, ec);
  if (ec) return Error{Error::Kind::io, "cannot write " + index.string() + ": " + ec.message()};
  return index.string();
}

// The Vulkan device the sheet is drawn on. Mesa keeps a shader cache under
// the home folder; the sheet writes only under its own folder.
Result<renderer::Context> sheet_context(bool software) {
  platform::set_env_default("MESA_SHADER_CACHE_DISABLE", "true");
  return from_renderer(renderer::Context::create(
      {.device = software ? renderer::DeviceChoice::software : renderer::DeviceChoice::automatic,
       .validation = false}));
}

}  // namespace

Result<PreviewResult> write_preview(const protocol::Protocol& p, const PreviewRequest& rq) {
  const protocol::Design design = protocol::expand_design(p, rq.participant);
  const auto conditions = preview_conditions(p, design);
  const auto report = [&](std::size_t done, const std::string& what) {
    if (rq.progress) rq.progress(done, conditions.size(), what);
  };
  const auto [w, h] = sheet_size(p, rq);
  std::error_code ec;
  const fs::path dir(rq.out_dir);
  fs::create_directories(dir / "images", ec);
  if (ec) return Error{Error::Kind::io, "cannot create " + (dir / "images").string() + ": " + ec.message()};

  auto context = sheet_context(rq.software);
  if (!context) return context.error();
  const auto& ctx = context.value();
  // Drawn as the runner draws on this device: the protocol's [viewing] msaa.
  renderer::Renderer r(ctx, {.msaa = p.session_settings().viewing.msaa});
  renderer::OffscreenTarget target(ctx, w, h);
  SheetRenderer sheet{r, target, w, h, dir};

  // Onset stereo pairs, one per condition.
  report(0, "");
  std::vector<Rendered> images;
  for (std::size_t k = 0; k < conditions.size(); ++k) {
    auto rendered = render_condition(p, design.trials[conditions[k].first_trial], k, sheet);
    if (!rendered) return rendered.error();
    images.push_back(std::move(rendered).value());
    report(k + 1, condition_title(conditions[k]));
  }

  // Predicted proportions from the simulated observer (choice and
  // staircase blocks; practice is not predicted).
  PredictOptions po;
  po.simulations = 1;  // proportions only; power is `curvlab predict`'s job
  std::optional<Prediction> prediction;
  std::string prediction_note;
  auto predicted = predict(p, po);
  if (!predicted) prediction_note = predicted.error().message;
  else prediction = std::move(predicted).value();

  std::ostringstream o;
  write_header(o, p, rq, design, conditions.size(), ctx.device_name(), w, h, r.msaa());
  write_blocks(o, p, design);
  write_responses(o, p, design);
  write_texts(o, p, design);
  o << "<h2>Conditions (" << conditions.size() << ")</h2>\n<p class=\"small\">Each stereo pair is the first "
       "frame of the stimulus as the headless runner renders it, seen by a participant standing at the "
       "nominal table (the same viewpoint `curvlab predict` uses); a monocular condition's other eye shows "
       "the background (the dominant eye is taken to be the right). Predicted proportions are the simulated "
       "observer's over a population of 400 observers.</p>\n<div class=\"conditions\">\n";
  for (std::size_t k = 0; k < conditions.size(); ++k)
    write_panel(o, k, conditions[k], images[k], design.trials[conditions[k].first_trial], prediction,
                prediction_note, dir);
  o << "</div>\n<p class=\"small\">Written by <code>curvlab preview</code>.</p>\n</body>\n</html>\n";
  auto index = write_atomically(dir, o.str());
  if (!index) return index.error();
  return PreviewResult{*index, conditions.size(), images.size() * 3, ctx.device_name()};
}

}  // namespace curvlab::harness::runner
