// The session start form (`curvlab start`): for labs that do not use the
// terminal, the desktop window asks for the participant's pseudonym, the
// protocol, the backend and a note, checks the pseudonym against the data
// file's participants, and hands back what `curvlab run` needs.
//
// StartForm is the form's state and rules, driven by key names as the
// window gives them (desktop.hpp, key_input); run_start_form() shows it in a
// window until it is filled in or closed. Not thread-safe.
#pragma once

#include "curvlab/harness/io/station.hpp"
#include "curvlab/harness/result.hpp"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::desktop {

struct KnownParticipant {
  std::string pseudonym;
  int sessions = 0;
};

struct StartChoices {
  std::string participant;
  std::string protocol;  // one of the offered files
  std::string backend;   // desktop, xr or headless
  std::string note;
  bool new_session = false;  // the pseudonym has sessions already, confirmed
};

struct StartFormSetup {
  std::string db;                          // shown, for the experimenter to check
  std::vector<std::string> protocols;      // files to choose from (at least one)
  std::vector<KnownParticipant> known;     // the data file's participants
  // A known pseudonym close to a new one ("P0l" → "P01"), or "".
  std::function<std::string(const std::string&)> similar_known;
};

class StartForm {
 public:
  explicit StartForm(StartFormSetup setup);

  // A key pressed ("a", "1", "shift", "backspace", "tab", "up", "enter"…);
  // releases matter for shift only.
  void key(const std::string& name, bool pressed);
  // What the window shows: the fields, the one being edited marked, how to
  // use the keys, and the form's last message.
  [[nodiscard]] std::string text() const;
  // Set once Enter started the session with every field good.
  [[nodiscard]] const std::optional<StartChoices>& chosen() const { return chosen_; }

 private:
  enum Field { participant, protocol, backend, note, count };
  void submit();
  void type(const std::string& name);

  StartFormSetup setup_;
  int field_ = participant;
  std::string participant_, note_;
  std::size_t protocol_ = 0, backend_ = 0;
  bool shift_ = false;
  bool confirming_ = false;  // Enter again starts despite the message
  std::string message_;
  std::optional<StartChoices> chosen_;
};

// Shows the form in the window (a head-locked panel, text_height_deg 2.4)
// until Enter starts a session (its choices) or the window is closed or
// Escape pressed (nullopt). A device failure throws as the display does.
std::optional<StartChoices> run_start_form(io::InteractiveDisplay& window, StartForm& form, const std::string& font);

}  // namespace curvlab::harness::desktop
