// The shared-play codec (messages.hpp): little-endian fixed-width fields,
// u16-length strings, u16-counted lists, every one bounded.
#include <curvlab/harness/net/messages.hpp>

#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <type_traits>

namespace curvlab::harness::net {
namespace {

constexpr std::uint8_t kMagic0 = 'C';
constexpr std::uint8_t kMagic1 = 'L';
constexpr std::size_t kMaxInitials = 8;

[[noreturn]] void contract(const char* what) {
  std::fprintf(stderr, "curvlab::harness::net::encode: %s\n", what);
  std::abort();
}

class Writer {
 public:
  // The fields in order, each little-endian at its own width.
  template <class... T>
  void put(T... v) {
    (put_one(v), ...);
  }
  void text(const std::string& s, std::size_t max, const char* field) {
    if (s.size() > max) contract(field);
    put(static_cast<std::uint16_t>(s.size()));
    out_.insert(out_.end(), s.begin(), s.end());
  }
  void count(std::size_t n, std::size_t max, const char* field) {
    if (n > max) contract(field);
    put(static_cast<std::uint16_t>(n));
  }
  std::vector<std::uint8_t>& bytes() { return out_; }

 private:
  template <class T>
  void put_one(T v) {
    static_assert(std::is_trivially_copyable_v<T>);
    if constexpr (std::is_floating_point_v<T>) {
      put_one(std::bit_cast<std::conditional_t<sizeof(T) == 8, std::uint64_t, std::uint32_t>>(v));
    } else if constexpr (std::is_enum_v<T>) {
      put_one(static_cast<std::underlying_type_t<T>>(v));
    } else {
      auto u = static_cast<std::make_unsigned_t<T>>(v);
      for (std::size_t i = 0; i < sizeof(T); ++i) {
        out_.push_back(static_cast<std::uint8_t>(u & 0xffu));
        if constexpr (sizeof(T) > 1) u = static_cast<decltype(u)>(u >> 8);
      }
    }
  }
  std::vector<std::uint8_t> out_;
};

// Reads fields until the first failure; after that every read is a no-op
// and failure() says why.
class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> b) : b_(b) {}
  template <class T>
  T get() {
    if constexpr (std::is_floating_point_v<T>) {
      using U = std::conditional_t<sizeof(T) == 8, std::uint64_t, std::uint32_t>;
      return std::bit_cast<T>(get<U>());
    } else if constexpr (std::is_enum_v<T>) {
      return static_cast<T>(get<std::underlying_type_t<T>>());
    } else {
      if (!need(sizeof(T))) return T{};
      std::make_unsigned_t<T> u = 0;
      for (std::size_t i = 0; i < sizeof(T); ++i)
        u = static_cast<decltype(u)>(u | (static_cast<decltype(u)>(b_[pos_ + i]) << (8 * i)));
      pos_ += sizeof(T);
      return static_cast<T>(u);
    }
  }
  // Fields read in order, each at its own type's width (no range checks).
  template <class... T>
  void read(T&... v) {
    ((v = get<T>()), ...);
  }
  double finite(double max = kMaxMagnitude) {
    const double v = get<double>();
    if (!std::isfinite(v) || std::fabs(v) > max) fail(DecodeFailure::bad_value);
    return v;
  }
  std::string text(std::size_t max) {
    const std::size_t n = get<std::uint16_t>();
    if (n > max) {
      fail(DecodeFailure::oversized);
      return {};
    }
    if (!need(n)) return {};
    std::string s(reinterpret_cast<const char*>(b_.data() + pos_), n);
    pos_ += n;
    // Printable text only: these strings reach messages and the database.
    for (unsigned char c : s)
      if (c < 0x20 || c == 0x7f) fail(DecodeFailure::bad_value);
    return s;
  }
  std::size_t count(std::size_t max, std::size_t bytes_each) {
    const std::size_t n = get<std::uint16_t>();
    if (n > max) {
      fail(DecodeFailure::oversized);
      return 0;
    }
    // A count larger than the bytes left is refused before anything is
    // allocated for it.
    if (!ok() || n * bytes_each > b_.size() - pos_) {
      fail(DecodeFailure::too_short);
      return 0;
    }
    return n;
  }
  void fail(DecodeFailure f) {
    if (failure_ == DecodeFailure::none) failure_ = f;
  }
  bool ok() const { return failure_ == DecodeFailure::none; }
  DecodeFailure failure() const { return failure_; }
  bool at_end() const { return pos_ == b_.size(); }

 private:
  bool need(std::size_t n) {
    if (!ok()) return false;
    if (b_.size() - pos_ < n) {
      fail(DecodeFailure::too_short);
      return false;
    }
    return true;
  }
  std::span<const std::uint8_t> b_;
  std::size_t pos_ = 0;
  DecodeFailure failure_ = DecodeFailure::none;
};

bool is_hex64(const std::string& s) {
  if (s.size() != 64) return false;
  for (char c : s)
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  return true;
}

// ---- Hello
void put_body(Writer& w, const Hello& h) {
  w.put(h.role);
  w.text(h.software_version, kMaxShortText, "Hello::software_version");
  w.text(h.protocol_sha256, kMaxShortText, "Hello::protocol_sha256");
  w.text(h.parameters_sha256, kMaxShortText, "Hello::parameters_sha256");
  w.text(h.initials, kMaxInitials, "Hello::initials");
  w.count(h.parameters.size(), kMaxParameters, "Hello::parameters");
  for (const auto& [k, v] : h.parameters) {
    w.text(k, kMaxShortText, "Hello::parameters name");
    w.text(v, kMaxShortText, "Hello::parameters value");
  }
  for (auto b : h.game_uuid) w.put(b);
  w.put(h.completed_shots);
}
Hello get_hello(Reader& r) {
  Hello h;
  h.role = r.get<Role>();
  if (h.role != Role::host && h.role != Role::join) r.fail(DecodeFailure::bad_value);
  h.software_version = r.text(kMaxShortText);
  h.protocol_sha256 = r.text(kMaxShortText);
  h.parameters_sha256 = r.text(kMaxShortText);
  if (r.ok() && (!is_hex64(h.protocol_sha256) || !is_hex64(h.parameters_sha256)))
    r.fail(DecodeFailure::bad_value);
  h.initials = r.text(kMaxInitials);
  const std::size_t n = r.count(kMaxParameters, 4);
  for (std::size_t i = 0; i < n && r.ok(); ++i) {
    std::string k = r.text(kMaxShortText);
    std::string v = r.text(kMaxShortText);
    h.parameters.emplace_back(std::move(k), std::move(v));
  }
  for (auto& b : h.game_uuid) b = r.get<std::uint8_t>();
  h.completed_shots = r.get<std::uint32_t>();
  return h;
}

// ---- PoseFrame
bool valid_kind(std::uint8_t k) { return k <= static_cast<std::uint8_t>(geometry::SpaceKind::H3); }

void put_body(Writer& w, const PoseFrame& p) {
  w.put(p.sequence, p.display_ns, static_cast<std::uint8_t>(p.space), p.radius_m, p.tracked);
  for (const auto& iso : p.pose)
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) w.put(iso.m[c][r]);
}
PoseFrame get_pose(Reader& r) {
  PoseFrame p;
  r.read(p.sequence, p.display_ns);
  const auto kind = r.get<std::uint8_t>();
  if (!valid_kind(kind)) r.fail(DecodeFailure::bad_value);
  p.space = static_cast<geometry::SpaceKind>(valid_kind(kind) ? kind : 1);
  p.radius_m = r.finite(1e6);
  if (r.ok() && !(p.radius_m > 0.0)) r.fail(DecodeFailure::bad_value);
  p.tracked = r.get<std::uint8_t>();
  if (p.tracked >= (1u << PoseFrame::kDevices)) r.fail(DecodeFailure::bad_value);
  for (auto& iso : p.pose)
    for (int c = 0; c < 4; ++c)
      for (int row = 0; row < 4; ++row) iso.m[c][row] = r.finite();
  if (!r.ok()) return p;
  // A tracked pose must be an isometry of the declared space; the tolerance
  // grows with the entries (far out in H3 they are large and the frame's
  // sender rounded them in double).
  const geometry::Space space{p.space, p.radius_m};
  for (int d = 0; d < PoseFrame::kDevices; ++d) {
    if (!(p.tracked & (1u << d))) continue;
    double big = 1.0;
    for (int c = 0; c < 4; ++c)
      for (int row = 0; row < 4; ++row) big = std::max(big, std::fabs(p.pose[d].m[c][row]));
    if (!(geometry::isometry_error(space, p.pose[d]) <= 1e-6 * big * big))
      r.fail(DecodeFailure::bad_value);
  }
  return p;
}

// ---- Shot
constexpr std::size_t kEventBytes = 8 + 1 + 4 * 2;
constexpr std::size_t kBallBytes = 2 * 8 + 2;
constexpr double kMaxNative_m = 1e3;

void put_body(Writer& w, const Shot& s) {
  w.put(s.shot_index, s.shooter, static_cast<std::uint8_t>(s.simulated ? 1 : 0), s.strike_ns, s.cue_ball,
        s.toward_x_m, s.toward_z_m, s.cue_speed_m_s, s.tip_side, s.tip_height);
  w.count(s.events.size(), kMaxEvents, "Shot::events");
  for (const auto& e : s.events) w.put(e.t_s, e.kind, e.a, e.b, e.cushion, e.pocket);
  w.count(s.rest.size(), kMaxBalls, "Shot::rest");
  for (const auto& b : s.rest) w.put(b.x_m, b.z_m, static_cast<std::uint8_t>(b.pocketed ? 1 : 0), b.pocket);
}
Shot get_shot(Reader& r) {
  Shot s;
  s.shot_index = r.get<std::uint32_t>();
  s.shooter = r.get<Role>();
  if (s.shooter != Role::host && s.shooter != Role::join) r.fail(DecodeFailure::bad_value);
  const auto simulated = r.get<std::uint8_t>();
  if (simulated > 1) r.fail(DecodeFailure::bad_value);
  s.simulated = simulated == 1;
  s.strike_ns = r.get<std::int64_t>();
  s.cue_ball = r.get<std::int32_t>();
  if (s.cue_ball < 0 || s.cue_ball >= static_cast<std::int32_t>(kMaxBalls)) r.fail(DecodeFailure::bad_value);
  s.toward_x_m = r.finite(kMaxNative_m);
  s.toward_z_m = r.finite(kMaxNative_m);
  s.cue_speed_m_s = r.finite(100.0);
  s.tip_side = r.finite(10.0);
  s.tip_height = r.finite(10.0);
  if (r.ok() && s.cue_speed_m_s < 0.0) r.fail(DecodeFailure::bad_value);
  const std::size_t ne = r.count(kMaxEvents, kEventBytes);
  s.events.reserve(ne);
  for (std::size_t i = 0; i < ne && r.ok(); ++i) {
    ShotEvent e;
    e.t_s = r.finite(1e6);
    r.read(e.kind, e.a, e.b, e.cushion, e.pocket);
    if (e.kind > 5) r.fail(DecodeFailure::bad_value);
    for (auto idx : {e.a, e.b, e.cushion, e.pocket})
      if (idx < -1 || idx >= static_cast<std::int16_t>(kMaxBalls)) r.fail(DecodeFailure::bad_value);
    s.events.push_back(e);
  }
  const std::size_t nb = r.count(kMaxBalls, kBallBytes);
  s.rest.reserve(nb);
  for (std::size_t i = 0; i < nb && r.ok(); ++i) {
    ShotBall b;
    b.x_m = r.finite(kMaxNative_m);
    b.z_m = r.finite(kMaxNative_m);
    const auto pocketed = r.get<std::uint8_t>();
    b.pocketed = pocketed == 1;
    b.pocket = r.get<std::int8_t>();
    if (pocketed > 1 || b.pocket < -1 || b.pocket >= static_cast<std::int8_t>(kMaxBalls))
      r.fail(DecodeFailure::bad_value);
    s.rest.push_back(b);
  }
  return s;
}

// ---- GameState, Ping, Pong, Bye
void put_body(Writer& w, const GameState& g) {
  for (auto b : g.game_uuid) w.put(b);
  w.put(g.phase, g.completed_shots, g.next_shooter, g.rack_seed, g.balls);
}
GameState get_game_state(Reader& r) {
  GameState g;
  for (auto& b : g.game_uuid) b = r.get<std::uint8_t>();
  r.read(g.phase, g.completed_shots, g.next_shooter, g.rack_seed, g.balls);
  if (static_cast<int>(g.phase) > 3 || static_cast<int>(g.next_shooter) > 1 || g.balls > kMaxBalls)
    r.fail(DecodeFailure::bad_value);
  return g;
}
void put_body(Writer& w, const Ping& p) {
  w.put(p.id, p.t1_ns);
}
Ping get_ping(Reader& r) {
  Ping p;
  r.read(p.id, p.t1_ns);
  return p;
}
void put_body(Writer& w, const Pong& p) {
  w.put(p.id, p.t1_ns, p.t2_ns, p.t3_ns);
}
Pong get_pong(Reader& r) {
  Pong p;
  r.read(p.id, p.t1_ns, p.t2_ns, p.t3_ns);
  return p;
}
void put_body(Writer& w, const Bye& b) {
  w.put(b.reason);
  w.text(b.text, kMaxLongText, "Bye::text");
}
Bye get_bye(Reader& r) {
  Bye b;
  b.reason = r.get<Bye::Reason>();
  if (static_cast<int>(b.reason) > 2) r.fail(DecodeFailure::bad_value);
  b.text = r.text(kMaxLongText);
  return b;
}

// ---- Avatar
void put_body(Writer& w, const Avatar& a) {
  if (a.width == 0 || a.height == 0 || a.width > kMaxAvatarSide || a.height > kMaxAvatarSide ||
      a.grey.size() != std::size_t{a.width} * a.height)
    contract("Avatar: 1 to kMaxAvatarSide pixels a side, width × height grey levels");
  w.put(a.width, a.height);
  for (auto g : a.grey) w.put(g);
}
Avatar get_avatar(Reader& r) {
  Avatar a;
  r.read(a.width, a.height);
  if (!r.ok()) return a;
  if (a.width == 0 || a.height == 0 || a.width > kMaxAvatarSide || a.height > kMaxAvatarSide) {
    r.fail(DecodeFailure::bad_value);
    return a;
  }
  const std::size_t n = std::size_t{a.width} * a.height;
  a.grey.resize(n);
  for (std::size_t i = 0; i < n && r.ok(); ++i) a.grey[i] = r.get<std::uint8_t>();
  return a;
}

}  // namespace

bool PoseFrame::operator==(const PoseFrame& o) const {
  if (sequence != o.sequence || display_ns != o.display_ns || space != o.space || radius_m != o.radius_m ||
      tracked != o.tracked)
    return false;
  for (int d = 0; d < kDevices; ++d)
    if (pose[d].m != o.pose[d].m) return false;
  return true;
}

std::string_view to_string(MessageType type) {
  switch (type) {
    case MessageType::hello: return "hello";
    case MessageType::pose: return "pose";
    case MessageType::shot: return "shot";
    case MessageType::game_state: return "game_state";
    case MessageType::ping: return "ping";
    case MessageType::pong: return "pong";
    case MessageType::bye: return "bye";
    case MessageType::avatar: return "avatar";
  }
  return "unknown";
}

std::string_view to_string(Role role) { return role == Role::host ? "host" : "join"; }

MessageType type_of(const Message& m) {
  return static_cast<MessageType>(m.index() + 1);  // the variant's order is the types' order
}

std::string_view to_string(DecodeFailure f) {
  switch (f) {
    case DecodeFailure::none: return "none";
    case DecodeFailure::too_short: return "too_short";
    case DecodeFailure::bad_magic: return "bad_magic";
    case DecodeFailure::unsupported_version: return "unsupported_version";
    case DecodeFailure::unknown_type: return "unknown_type";
    case DecodeFailure::oversized: return "oversized";
    case DecodeFailure::length_mismatch: return "length_mismatch";
    case DecodeFailure::bad_value: return "bad_value";
    case DecodeFailure::trailing_bytes: return "trailing_bytes";
  }
  return "unknown";
}

std::uint64_t DropCounters::total() const {
  std::uint64_t n = 0;
  for (std::size_t i = 1; i < by_reason.size(); ++i) n += by_reason[i];
  return n;
}

std::vector<std::uint8_t> encode(const Message& m) {
  Writer w;
  w.put(kMagic0);
  w.put(kMagic1);
  w.put(kCodecVersion);
  w.put(type_of(m));
  w.put(std::uint32_t{0});  // the payload's length, filled in below
  std::visit([&w](const auto& body) { put_body(w, body); }, m);
  auto& out = w.bytes();
  if (out.size() > kMaxMessageBytes) contract("message beyond kMaxMessageBytes");
  const auto n = static_cast<std::uint32_t>(out.size() - kHeaderBytes);
  for (int i = 0; i < 4; ++i) out[4 + i] = static_cast<std::uint8_t>((n >> (8 * i)) & 0xffu);
  return std::move(out);
}

Decoded decode(std::span<const std::uint8_t> bytes) {
  if (bytes.size() > kMaxMessageBytes) return {std::nullopt, DecodeFailure::oversized};
  if (bytes.size() < kHeaderBytes) return {std::nullopt, DecodeFailure::too_short};
  if (bytes[0] != kMagic0 || bytes[1] != kMagic1) return {std::nullopt, DecodeFailure::bad_magic};
  if (bytes[2] != kCodecVersion) return {std::nullopt, DecodeFailure::unsupported_version};
  const std::uint8_t type = bytes[3];
  if (type < 1 || type > static_cast<std::uint8_t>(MessageType::avatar)) return {std::nullopt, DecodeFailure::unknown_type};
  std::uint32_t n = 0;
  for (int i = 0; i < 4; ++i) n |= static_cast<std::uint32_t>(bytes[4 + i]) << (8 * i);
  if (n != bytes.size() - kHeaderBytes) return {std::nullopt, DecodeFailure::length_mismatch};

  Reader r(bytes.subspan(kHeaderBytes));
  Message m;
  switch (static_cast<MessageType>(type)) {
    case MessageType::hello: m = get_hello(r); break;
    case MessageType::pose: m = get_pose(r); break;
    case MessageType::shot: m = get_shot(r); break;
    case MessageType::game_state: m = get_game_state(r); break;
    case MessageType::ping: m = get_ping(r); break;
    case MessageType::pong: m = get_pong(r); break;
    case MessageType::bye: m = get_bye(r); break;
    case MessageType::avatar: m = get_avatar(r); break;
  }
  if (!r.ok()) return {std::nullopt, r.failure()};
  if (!r.at_end()) return {std::nullopt, DecodeFailure::trailing_bytes};
  return {std::move(m), DecodeFailure::none};
}

}  // namespace curvlab::harness::net
