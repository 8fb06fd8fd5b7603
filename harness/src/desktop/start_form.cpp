#include "curvlab/harness/desktop/start_form.hpp"

#include "curvlab/renderer/plan.hpp"
#include "curvlab/renderer/scene.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>

namespace curvlab::harness::desktop {
namespace {

constexpr std::array<const char*, 3> kBackends{"desktop", "xr", "headless"};
constexpr const char* kBackendMeaning[] = {"this window, keyboard and mouse", "the headset (OpenXR)",
                                           "no display, the simulated participant"};
constexpr std::size_t kLongestNote = 200;
constexpr std::size_t kLongestPseudonym = 32;

// The character a key types into a field, "" for none.
std::string typed(const std::string& name, bool shift, bool in_note) {
  if (name.size() == 1 && std::isalnum(static_cast<unsigned char>(name[0])))
    return std::string(1, shift ? static_cast<char>(std::toupper(static_cast<unsigned char>(name[0]))) : name[0]);
  if (name == "minus") return "-";
  if (!in_note) return "";
  if (name == "space") return " ";
  if (name == "comma") return ",";
  if (name == "period") return ".";
  if (name == "slash") return "/";
  if (name == "semicolon") return ";";
  return "";
}

}  // namespace

StartForm::StartForm(StartFormSetup setup) : setup_(std::move(setup)) {}

void StartForm::key(const std::string& name, bool pressed) {
  if (name == "shift" || name == "left_shift" || name == "right_shift") {
    shift_ = pressed;
    return;
  }
  if (!pressed || chosen_) return;
  if (name == "enter" || name == "kp_enter") return submit();
  if (name == "tab" || name == "down") {
    field_ = (field_ + 1) % count;
  } else if (name == "up") {
    field_ = (field_ + count - 1) % count;
  } else if ((name == "left" || name == "right") && (field_ == protocol || field_ == backend)) {
    const std::size_t n = field_ == protocol ? setup_.protocols.size() : kBackends.size();
    std::size_t& at = field_ == protocol ? protocol_ : backend_;
    at = (at + (name == "right" ? 1 : n - 1)) % n;
  } else {
    type(name);
    return;
  }
  confirming_ = false;
  message_.clear();
}

void StartForm::type(const std::string& name) {
  std::string* text = field_ == participant ? &participant_ : field_ == note ? &note_ : nullptr;
  if (text == nullptr) return;
  const std::size_t limit = field_ == participant ? kLongestPseudonym : kLongestNote;
  if (name == "backspace") {
    if (!text->empty()) text->pop_back();
  } else if (const std::string c = typed(name, shift_, field_ == note); !c.empty() && text->size() < limit) {
    *text += c;
  } else {
    return;
  }
  if (field_ == participant) {
    confirming_ = false;
    message_.clear();
  }
}

void StartForm::submit() {
  if (participant_.empty()) {
    field_ = participant;
    message_ = "Type the participant's pseudonym first.";
    return;
  }
  const auto known = std::find_if(setup_.known.begin(), setup_.known.end(),
                                  [&](const KnownParticipant& k) { return k.pseudonym == participant_; });
  if (!confirming_) {
    if (known != setup_.known.end()) {
      confirming_ = true;
      message_ = participant_ + " already has " + std::to_string(known->sessions) +
                 (known->sessions == 1 ? " session" : " sessions") +
                 " in this file (the same trial order). Enter again starts another; Backspace corrects the pseudonym.";
      return;
    }
    if (const std::string near = setup_.similar_known ? setup_.similar_known(participant_) : ""; !near.empty()) {
      confirming_ = true;
      message_ = participant_ + " is new, and close to " + near + ", who is in this file. Enter again adds " +
                 participant_ + " as a new participant; Backspace corrects it.";
      return;
    }
  }
  chosen_ = StartChoices{participant_, setup_.protocols.at(protocol_), kBackends.at(backend_), note_,
                         known != setup_.known.end()};
}

std::string StartForm::text() const {
  auto mark = [&](int f) { return std::string(field_ == f ? "▶ " : "   "); };
  const auto known = std::find_if(setup_.known.begin(), setup_.known.end(),
                                  [&](const KnownParticipant& k) { return k.pseudonym == participant_; });
  std::string who = participant_.empty() ? "(type the pseudonym)"
                    : known == setup_.known.end()
                        ? participant_ + "   (new)"
                        : participant_ + "   (" + std::to_string(known->sessions) + " earlier)";
  const std::string file = std::filesystem::path(setup_.protocols.at(protocol_)).filename().string();
  std::string out = "Start a session\nData file: " + setup_.db + "\n\n";
  out += mark(participant) + "Participant:  " + who + (field_ == participant ? "_" : "") + "\n";
  out += mark(protocol) + "Protocol:  ◀ " + file + " ▶   (" + std::to_string(protocol_ + 1) + " of " +
         std::to_string(setup_.protocols.size()) + ")\n";
  out += mark(backend) + "Backend:  ◀ " + kBackends.at(backend_) + " ▶   " + kBackendMeaning[backend_] + "\n";
  out += mark(note) + "Note:  " + (note_.empty() && field_ != note ? "(none)" : note_) + (field_ == note ? "_" : "") +
         "\n\n";
  out += "Tab or ↑ ↓: next field     ← →: choose     Enter: start     Esc: close";
  if (!message_.empty()) out += "\n\n" + message_;
  return out;
}

std::optional<StartChoices> run_start_form(io::InteractiveDisplay& window, StartForm& form, const std::string& font) {
  renderer::Scene scene;
  std::string shown;
  std::vector<io::InputEvent> inputs;
  for (;;) {
    const auto timing = window.begin_frame();
    if (!timing) return std::nullopt;
    inputs.clear();
    if (window.poll(inputs) == io::Signal::quit) return std::nullopt;
    for (const auto& in : inputs) form.key(in.control.name, in.pressed);
    if (form.chosen()) return form.chosen();
    if (const std::string text = form.text(); text != shown) {
      const double px_per_deg = std::max(5.0, static_cast<double>(window.info().eye_width_px) / 90.0);
      auto made = renderer::head_panel_object(
          "start form", text, font,
          {.text_height_deg = 2.4, .max_width_deg = 84.0, .elevation_deg = 0.0, .px_per_deg = px_per_deg});
      if (auto* e = std::get_if<renderer::RenderError>(&made)) throw io::DeviceFailure("start form", "font", e->message);
      scene = renderer::Scene{};
      scene.add(std::move(std::get<renderer::SceneObject>(made)));
      shown = text;
    }
    renderer::FrameDescription f;
    f.rig = window.rig(*timing, 0.063);
    window.submit(scene, f, io::Overlay{io::Phase::instructions, "start form", true}, true);
  }
}

}  // namespace curvlab::harness::desktop
