// The messages two stations of a shared play block exchange (docs/shared_play.md),
// and their one binary codec.
//
// Every message is a header — magic "CL", codec version, type, payload length
// (u32, little-endian) — and a payload of fixed-width little-endian fields,
// length-prefixed strings and counted lists. Every field has a bound: a string
// its longest length, a list its most entries, a message kMaxMessageBytes in
// all, a number its range (finite, isometries of the declared space). decode()
// checks all of them and returns the reason for the first one broken; the
// caller drops the message and counts the reason (DropCounters). Nothing that
// arrives from the network is used before it has been decoded here.
//
// A message of a newer codec version is refused (unsupported_version), never
// guessed at: both stations must run the same curvlab version (handshake.hpp),
// and the version in the header lets the refusal say so.
//
// Pure: no I/O, no global state; safe to call from any thread.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include <curvlab/geometry/isometry.hpp>

namespace curvlab::harness::net {

inline constexpr std::uint8_t kCodecVersion = 1;
inline constexpr std::size_t kHeaderBytes = 8;
inline constexpr std::size_t kMaxMessageBytes = 64 * 1024;
inline constexpr std::size_t kMaxShortText = 64;    // names, versions, hashes
inline constexpr std::size_t kMaxLongText = 512;    // a refusal or farewell
inline constexpr std::size_t kMaxParameters = 128;  // Hello::parameters
inline constexpr std::size_t kMaxEvents = 2048;     // Shot::events
inline constexpr std::size_t kMaxBalls = 32;        // Shot::rest, GameState
inline constexpr std::size_t kMaxAvatarSide = 128;  // Avatar: at most 128 × 128 grey levels
// A pose's isometry entries and a strike's numbers beyond this are refused:
// H3 isometries 40 radians from the origin have entries near 1e17 and the
// table is a few radians across.
inline constexpr double kMaxMagnitude = 1e12;

enum class MessageType : std::uint8_t {
  hello = 1,
  pose = 2,
  shot = 3,
  game_state = 4,
  ping = 5,
  pong = 6,
  bye = 7,
  avatar = 8,
};
std::string_view to_string(MessageType type);

enum class Role : std::uint8_t { host = 0, join = 1 };
std::string_view to_string(Role role);

using Uuid = std::array<std::uint8_t, 16>;

// Sent first by both stations; each compares the other's with its own
// (handshake.hpp) before anything is written.
struct Hello {
  Role role = Role::host;
  std::string software_version;     // curvlab's version, e.g. "0.1.0"
  std::string protocol_sha256;      // 64 lowercase hex digits
  std::string parameters_sha256;    // of the canonical parameter text (handshake.hpp)
  std::string initials;             // drawn on the partner's avatar; ≤ 8 bytes
  // The parameters that must agree, as name = value text, sorted by name.
  std::vector<std::pair<std::string, std::string>> parameters;
  // A station rejoining a game it was part of sends that game's id and its
  // last completed shot; a new game sends zeros and 0.
  Uuid game_uuid{};
  std::uint32_t completed_shots = 0;
  bool operator==(const Hello&) const = default;
};

// Head, hands and cue as the sender's tracking placed them in the curved
// space, every frame (unreliable, sequenced). Times are the sender's session
// clock; the receiver maps them through its clock estimate (clock_sync.hpp).
struct PoseFrame {
  enum Device : std::uint8_t { head = 0, left_hand = 1, right_hand = 2, cue = 3 };
  static constexpr int kDevices = 4;
  std::uint32_t sequence = 0;
  std::int64_t display_ns = 0;       // the frame's predicted display time (sender's clock)
  geometry::SpaceKind space = geometry::SpaceKind::E3;
  double radius_m = 1.0;
  std::uint8_t tracked = 0;          // bit d set: device d's pose is valid
  std::array<geometry::Isometry, kDevices> pose{};
  bool operator==(const PoseFrame& o) const;  // every entry equal
};

// A shot as the shooter's station struck and simulated it: the strike's
// inputs (what the other station re-simulates from), the events and the rest
// state its simulation gave (what it compares with, or takes).
struct ShotBall {
  double x_m = 0.0, z_m = 0.0;  // native coordinates on the cloth (docs/billiards.md)
  bool pocketed = false;
  std::int8_t pocket = -1;
  bool operator==(const ShotBall&) const = default;
};
struct ShotEvent {
  double t_s = 0.0;
  std::uint8_t kind = 0;  // billiards::EventKind
  std::int16_t a = -1, b = -1, cushion = -1, pocket = -1;
  bool operator==(const ShotEvent&) const = default;
};
struct Shot {
  std::uint32_t shot_index = 0;     // 0-based, in the game
  Role shooter = Role::host;
  bool simulated = false;           // the shooter's simulated player shot it (else its participant)
  std::int64_t strike_ns = 0;       // the shooter's session clock
  std::int32_t cue_ball = 0;
  // The cue ball leaves along the geodesic toward this native point (the
  // stored form of an aim, billiards::ShotSpec::toward_m), bit for bit what
  // the shooter simulated.
  double toward_x_m = 0.0, toward_z_m = 0.0;
  double cue_speed_m_s = 0.0;
  double tip_side = 0.0, tip_height = 0.0;  // fractions of the ball's radius
  std::vector<ShotEvent> events;
  std::vector<ShotBall> rest;
  bool operator==(const Shot&) const = default;
};

// Turn-taking and rack, shared (reliable). The host's copy is the game's.
struct GameState {
  enum class Phase : std::uint8_t { waiting = 0, playing = 1, paused = 2, over = 3 };
  Uuid game_uuid{};
  Phase phase = Phase::waiting;
  std::uint32_t completed_shots = 0;
  Role next_shooter = Role::host;
  std::uint64_t rack_seed = 0;
  std::uint16_t balls = 0;           // on the table at the rack
  bool operator==(const GameState&) const = default;
};

// NTP-style clock exchange (clock_sync.hpp): t1 the pinger's send time, t2
// and t3 the ponger's receive and send times, each on its own clock.
struct Ping {
  std::uint32_t id = 0;
  std::int64_t t1_ns = 0;
  bool operator==(const Ping&) const = default;
};
struct Pong {
  std::uint32_t id = 0;
  std::int64_t t1_ns = 0, t2_ns = 0, t3_ns = 0;
  bool operator==(const Pong&) const = default;
};

struct Bye {
  enum class Reason : std::uint8_t { done = 0, incompatible = 1, quitting = 2 };
  Reason reason = Reason::done;
  std::string text;
  bool operator==(const Bye&) const = default;
};

// The player's photo, sent once after each hello, drawn on the face of the
// partner's avatar: grey levels (0 black, 255 white), row major from the top.
struct Avatar {
  std::uint16_t width = 0, height = 0;  // 1 … kMaxAvatarSide each
  std::vector<std::uint8_t> grey;       // width × height
  bool operator==(const Avatar&) const = default;
};

using Message = std::variant<Hello, PoseFrame, Shot, GameState, Ping, Pong, Bye, Avatar>;
MessageType type_of(const Message& m);

// Why a message was dropped.
enum class DecodeFailure : std::uint8_t {
  none = 0,
  too_short,            // shorter than the header or a field
  bad_magic,
  unsupported_version,
  unknown_type,
  oversized,            // beyond kMaxMessageBytes, or a bound of a list or string
  length_mismatch,      // the header's length is not the bytes there
  bad_value,            // a field out of its range (not finite, not an isometry, …)
  trailing_bytes,       // the payload has more than its fields
};
inline constexpr int kDecodeFailures = 9;
std::string_view to_string(DecodeFailure f);

struct Decoded {
  std::optional<Message> message;
  DecodeFailure failure = DecodeFailure::none;
};

// Encoding a message that breaks a bound (a string too long, too many
// events) is a broken contract: it aborts naming the field. Callers bound
// their own data first (the play block has at most kMaxBalls balls).
std::vector<std::uint8_t> encode(const Message& m);
Decoded decode(std::span<const std::uint8_t> bytes);

// Messages dropped, by reason. Not thread-safe; one per receiving thread.
struct DropCounters {
  std::array<std::uint64_t, kDecodeFailures> by_reason{};
  void count(DecodeFailure f) { ++by_reason[static_cast<std::size_t>(f)]; }
  std::uint64_t total() const;
};

}  // namespace curvlab::harness::net
