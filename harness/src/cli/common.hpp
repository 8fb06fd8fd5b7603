// Shared pieces of the command line: the error kinds that map to exit codes,
// and output that is human-readable by default and JSON with --json.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "curvlab/geometry/space.hpp"
#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/result.hpp"

namespace CLI {
class App;
}

namespace curvlab::harness::cli {

// Bad arguments or input a person must fix: message on stderr, exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// An expected failure at run time (no device, disk full…): exit code 1, or
// 128 + N after signal N ended a session.
struct RuntimeFailure : std::runtime_error {
  explicit RuntimeFailure(const std::string& message, int code = 1) : std::runtime_error(message), exit_code(code) {}
  int exit_code = 1;
};

using Json = nlohmann::ordered_json;

// Throws an Error from any library as the matching CLI failure: UsageError
// when harness::exit_code() says 2 (bad input: a missing, damaged or foreign
// file…), RuntimeFailure otherwise.
[[noreturn]] void raise(const harness::Error& e);

// Refuses a --db file that is not SQLite, or damaged or truncated, before a
// command starts a window or headset (data::check_data_file): exit 2.
void check_db_argument(const std::string& path);

// Prints `doc` as indented JSON, or as aligned "key: value" lines.
void print_result(const Json& doc, bool as_json);

// The participant number (counterbalancing row and seed) of `run`, `design`
// and `preview`: `number` (--participant-number) when given, else the
// pseudonym's trailing number (P07 → 7, a plain 7 → 7, none → 1). A
// trailing number of 0 or one too large for a seed is a UsageError naming
// --participant and asking for --participant-number.
std::uint64_t participant_number(const std::string& participant, std::optional<std::uint64_t> number);

// A mistyped command or option, found before CLI11 parses (which would say
// "A subcommand is required" or name a required option instead): the
// message with a did-you-mean, nullopt when every word is known or no
// known one is close (CLI11's own message follows then).
std::optional<std::string> misspelt_argument(CLI::App& app, int argc, const char* const* argv);

// Called first in main: a write to a pipe whose reader has gone fails with
// EPIPE instead of killing the process with SIGPIPE, so a session whose
// --progress json reader exits ends interrupted and resumable instead of
// being left stored as running (POSIX; Windows has no SIGPIPE).
void ignore_broken_pipes();

// Parses "x,y,z,w" (or any count) into doubles; throws UsageError naming the
// option on failure.
std::vector<double> parse_number_list(const std::string& text, const std::string& option,
                                      std::size_t expected_count);

// Adds the required option `--space S3|E3|H3` (case-insensitive) to cmd.
void add_space_option(CLI::App* cmd, geometry::SpaceKind* kind);
// --msaa N: samples per pixel, 1, 2, 4 or 8; a UsageError naming --msaa
// otherwise.
std::uint32_t check_msaa(int samples);
// --msaa auto|N: nullopt for "auto" (the device's automatic count), else
// check_msaa of the number.
std::optional<std::uint32_t> parse_msaa(const std::string& text);
// A warning on stderr when the device draws with fewer samples than asked.
void warn_if_msaa_clamped(std::uint32_t requested, std::uint32_t effective);

// "WIDTHxHEIGHT" in pixels, each 16…8192; a UsageError naming `option` otherwise.
std::pair<std::uint32_t, std::uint32_t> parse_size(const std::string& text, const std::string& option);

// Registration of each command group (one file each, wired in main.cpp).
void add_inspect_commands(CLI::App& app);
void add_devices_commands(CLI::App& app);
void add_export_commands(CLI::App& app);
void add_sessions_commands(CLI::App& app);  // sessions, participants: what a data file holds
// `run` of a pseudonym that already has a session in `db` (the participant
// registry): a UsageError naming the earlier sessions and asking for
// --new-session. Nothing when the file does not exist yet or the pseudonym
// is new.
// `path` as one shell word: quoted when it holds anything a shell reads.
std::string shell_word(const std::string& path);
void check_participant_is_new(const std::string& db, const std::string& pseudonym);
// Each pseudonym of a data file with its number of sessions, in order of
// first session; none when the file does not exist yet.
std::vector<std::pair<std::string, int>> participants_in(const std::string& db);
void add_merge_commands(CLI::App& app);
// Database arguments of merge and export: each folder is replaced by the
// *.sqlite files directly in it (sorted by name), leaving out `exclude`.
std::vector<std::string> expand_database_args(const std::vector<std::string>& args, const std::string& exclude);
void add_track_commands(CLI::App& app);  // trajectory, track, inspect vergence/stick
void add_render_commands(CLI::App& app);
void add_measure_commands(CLI::App& app);  // measure stick
void add_protocol_commands(CLI::App& app);
void add_authoring_commands(CLI::App& app);  // schema, new, preview
void add_run_commands(CLI::App& app);
// What the start form chose, run as `curvlab run` would with these options.
struct FormRun {
  std::string protocol, participant, db, backend, note, window_size;
  bool new_session = false;
  bool software = false;
};
void run_from_form(const FormRun& f);
void add_start_command(CLI::App& app);  // curvlab start (start.cpp)  // run, resume, then predict and replay:
void add_predict_command(CLI::App& app);
void add_replay_command(CLI::App& app);
void add_calibrate_commands(CLI::App& app);  // calibrate: the physical table
void add_billiards_commands(CLI::App& app);  // billiards shot, billiards rack
// Reads and loads a protocol file, or prints every diagnostic and throws a
// UsageError (exit 2). `text`, when given, receives the text that was loaded
// (sessions store it).
harness::protocol::Protocol load_protocol_or_usage(const std::string& path, std::string* text = nullptr);  // run, resume, predict, replay

}  // namespace curvlab::harness::cli
