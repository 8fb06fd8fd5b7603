// The ENet link (link.hpp). Built without ENet, the same interface refuses
// to listen or join, saying how to build it in.
#include <curvlab/harness/net/link.hpp>

#include <charconv>
#include <mutex>

#ifdef CURVLAB_WITH_ENET
#include <enet/enet.h>
#endif

namespace curvlab::harness::net {

Result<std::pair<std::string, std::uint16_t>> Link::parse_address(const std::string& text) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size())
    return Error{Error::Kind::usage, "--partner: expected HOST:PORT (e.g. 192.168.1.20:7777), got '" + text + "'"};
  const std::string port_text = text.substr(colon + 1);
  unsigned port = 0;
  const auto [end, ec] = std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (ec != std::errc{} || end != port_text.data() + port_text.size() || port == 0 || port > 65535)
    return Error{Error::Kind::usage, "--partner: the port must be 1 to 65535, got '" + port_text + "'"};
  return std::pair<std::string, std::uint16_t>{text.substr(0, colon), static_cast<std::uint16_t>(port)};
}

#ifdef CURVLAB_WITH_ENET

namespace {

enum Channel : enet_uint8 { kPoses = 0, kReliable = 1, kClock = 2, kChannels = 3 };

bool initialise_enet() {
  static std::once_flag once;
  static bool ok = false;
  // Never deinitialised: other links may live until exit, and the OS frees
  // the sockets (on Windows, WSACleanup at exit is optional).
  std::call_once(once, [] { ok = enet_initialize() == 0; });
  return ok;
}

struct HostDeleter {
  void operator()(ENetHost* h) const { enet_host_destroy(h); }
};

}  // namespace

bool built_with_enet() { return true; }
std::string enet_description() {
  std::string s = "ENet ";
  s += std::to_string(ENET_VERSION_MAJOR);
  s += '.';
  s += std::to_string(ENET_VERSION_MINOR);
  s += '.';
  s += std::to_string(ENET_VERSION_PATCH);
  return s;
}

struct Link::Impl {
  const io::Clock* clock = nullptr;
  LinkOptions options;
  std::unique_ptr<ENetHost, HostDeleter> host;
  ENetPeer* peer = nullptr;  // the partner; owned by host
  bool is_host = false;
  ENetAddress remote{};
  LinkCounters counters;
  ClockEstimator estimator;
  std::uint32_t next_ping = 1;
  std::int64_t last_ping_ns = 0;
  bool pose_seen = false;
  std::uint32_t last_pose_sequence = 0;

  Impl(const io::Clock& c, LinkOptions o) : clock(&c), options(o), estimator(o.clock_window) {}

  void send_raw(const Message& m) {
    const auto bytes = encode(m);
    const MessageType t = type_of(m);
    enet_uint8 channel = kReliable;
    enet_uint32 flags = ENET_PACKET_FLAG_RELIABLE;
    if (t == MessageType::pose) {
      channel = kPoses;
      flags = 0;
    } else if (t == MessageType::ping || t == MessageType::pong) {
      channel = kClock;
      flags = ENET_PACKET_FLAG_UNSEQUENCED;
    }
    ENetPacket* packet = enet_packet_create(bytes.data(), bytes.size(), flags);
    if (packet == nullptr) return;
    if (enet_peer_send(peer, channel, packet) != 0) {
      enet_packet_destroy(packet);
      return;
    }
    ++counters.datagrams_sent;
    counters.bytes_sent += bytes.size();
  }

  bool is_connected() const { return peer != nullptr && peer->state == ENET_PEER_STATE_CONNECTED; }

  void maybe_ping() {
    if (!is_connected()) return;
    const std::int64_t now = clock->now_ns();
    if (last_ping_ns != 0 && now - last_ping_ns < options.ping_interval_ns) return;
    last_ping_ns = now;
    send_raw(Ping{next_ping++, now});
  }

  void on_receive(ENetEvent& ev, Poll& out) {
    const std::int64_t received_ns = clock->now_ns();
    ++counters.datagrams_received;
    counters.bytes_received += ev.packet->dataLength;
    Decoded d = decode({ev.packet->data, ev.packet->dataLength});
    enet_packet_destroy(ev.packet);
    if (ev.peer != peer) return;  // a stale partner's last words
    if (!d.message) {
      counters.dropped.count(d.failure);
      return;
    }
    Message& m = *d.message;
    if (auto* ping = std::get_if<Ping>(&m)) {
      send_raw(Pong{ping->id, ping->t1_ns, received_ns, clock->now_ns()});
      enet_host_flush(host.get());
      return;
    }
    if (auto* pong = std::get_if<Pong>(&m)) {
      estimator.add(*pong, received_ns);
      return;
    }
    if (auto* pose = std::get_if<PoseFrame>(&m)) {
      if (pose_seen && pose->sequence <= last_pose_sequence) {
        ++counters.poses_late;
        return;
      }
      if (pose_seen) counters.poses_lost += pose->sequence - last_pose_sequence - 1;
      pose_seen = true;
      last_pose_sequence = pose->sequence;
      ++counters.poses_received;
    }
    out.messages.push_back({std::move(m), received_ns});
  }

  void on_connect(ENetEvent& ev, Poll& out) {
    if (peer != nullptr && peer != ev.peer) {
      // A partner that comes back (a killed station restarted) replaces the
      // one ENet has not yet timed out: the old one is gone, reported so.
      enet_peer_reset(peer);
      ++counters.disconnects;
      out.disconnected = true;
    }
    peer = ev.peer;
    enet_peer_timeout(peer, 0, options.timeout_ms, options.timeout_ms);
    ++counters.connects;
    pose_seen = false;
    last_ping_ns = 0;
    out.connected = true;
  }

  void on_disconnect(ENetEvent& ev, Poll& out) {
    if (ev.peer != peer) return;
    peer = nullptr;
    ++counters.disconnects;
    out.disconnected = true;
  }
};

Link::Link(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Link::Link(Link&&) noexcept = default;
Link& Link::operator=(Link&&) noexcept = default;
Link::~Link() {
  if (impl_ && impl_->is_connected()) {
    enet_peer_disconnect_now(impl_->peer, 0);
    enet_host_flush(impl_->host.get());
  }
}

Result<Link> Link::listen(const std::string& bind_address, std::uint16_t port, const io::Clock& clock,
                          LinkOptions options) {
  if (!initialise_enet()) return Error{Error::Kind::device, "cannot initialise ENet (the network library)"};
  ENetAddress address{};
  address.port = port;
  if (bind_address.empty() || bind_address == "0.0.0.0") {
    address.host = ENET_HOST_ANY;
  } else if (enet_address_set_host_ip(&address, bind_address.c_str()) != 0) {
    return Error{Error::Kind::usage, "cannot listen on '" + bind_address + "': not an IPv4 address"};
  }
  auto impl = std::make_unique<Impl>(clock, options);
  impl->is_host = true;
  // Two peers: the partner, and room for it to come back while ENet still
  // holds the stale one.
  impl->host.reset(enet_host_create(&address, 2, kChannels, 0, 0));
  if (!impl->host) {
    return Error{Error::Kind::io, "cannot listen on UDP port " + std::to_string(port) +
                                      ": it is in use or not allowed (choose another with --listen)"};
  }
  impl->host->maximumPacketSize = kMaxMessageBytes;
  return Link(std::move(impl));
}

Result<Link> Link::join(const std::string& host_name, std::uint16_t port, const io::Clock& clock,
                        LinkOptions options) {
  if (!initialise_enet()) return Error{Error::Kind::device, "cannot initialise ENet (the network library)"};
  auto impl = std::make_unique<Impl>(clock, options);
  impl->remote.port = port;
  if (enet_address_set_host(&impl->remote, host_name.c_str()) != 0)
    return Error{Error::Kind::usage, "--partner: cannot resolve host '" + host_name + "'"};
  impl->host.reset(enet_host_create(nullptr, 1, kChannels, 0, 0));
  if (!impl->host) return Error{Error::Kind::io, "cannot open a UDP socket for the link to the partner"};
  impl->host->maximumPacketSize = kMaxMessageBytes;
  Link link(std::move(impl));
  link.reconnect();
  return link;
}

bool Link::connected() const { return impl_->is_connected(); }

std::uint16_t Link::port() const {
  ENetAddress a{};
  if (enet_socket_get_address(impl_->host->socket, &a) != 0) return impl_->host->address.port;
  return a.port;
}

void Link::reconnect() {
  if (impl_->is_host || impl_->is_connected()) return;
  if (impl_->peer != nullptr) enet_peer_reset(impl_->peer);
  impl_->peer = enet_host_connect(impl_->host.get(), &impl_->remote, kChannels, 0);
}

bool Link::send(const Message& m) {
  if (!impl_->is_connected()) return false;
  impl_->send_raw(m);
  return true;
}

void Link::flush() { enet_host_flush(impl_->host.get()); }

Poll Link::poll(int timeout_ms) {
  Poll out;
  impl_->maybe_ping();
  ENetEvent ev;
  int r = enet_host_service(impl_->host.get(), &ev, timeout_ms < 0 ? 0u : static_cast<enet_uint32>(timeout_ms));
  while (r > 0) {
    switch (ev.type) {
      case ENET_EVENT_TYPE_CONNECT:
        // The joiner's connect event is for its own peer; the host's for a
        // new partner.
        impl_->on_connect(ev, out);
        break;
      case ENET_EVENT_TYPE_RECEIVE: impl_->on_receive(ev, out); break;
      case ENET_EVENT_TYPE_DISCONNECT: impl_->on_disconnect(ev, out); break;
      case ENET_EVENT_TYPE_NONE: break;
    }
    r = enet_host_check_events(impl_->host.get(), &ev);
  }
  impl_->maybe_ping();
  enet_host_flush(impl_->host.get());
  // ENet's totals are 32-bit: moved into ours at every poll.
  impl_->counters.wire_bytes_sent += impl_->host->totalSentData;
  impl_->counters.wire_bytes_received += impl_->host->totalReceivedData;
  impl_->host->totalSentData = 0;
  impl_->host->totalReceivedData = 0;
  return out;
}

void Link::wait_readable(int timeout_ms) const {
  enet_uint32 condition = ENET_SOCKET_WAIT_RECEIVE;
  (void)enet_socket_wait(impl_->host->socket, &condition, timeout_ms < 0 ? 0u : static_cast<enet_uint32>(timeout_ms));
}

void Link::close(const Bye& bye, int timeout_ms) {
  if (!impl_->is_connected()) return;
  impl_->send_raw(bye);
  enet_peer_disconnect_later(impl_->peer, 0);
  const std::int64_t end = impl_->clock->now_ns() + std::int64_t{timeout_ms} * 1'000'000;
  ENetEvent ev;
  while (impl_->peer != nullptr && impl_->clock->now_ns() < end) {
    if (enet_host_service(impl_->host.get(), &ev, 10) > 0) {
      if (ev.type == ENET_EVENT_TYPE_RECEIVE) enet_packet_destroy(ev.packet);
      if (ev.type == ENET_EVENT_TYPE_DISCONNECT && ev.peer == impl_->peer) impl_->peer = nullptr;
    }
  }
  if (impl_->peer != nullptr) {
    enet_peer_reset(impl_->peer);
    impl_->peer = nullptr;
  }
}

LinkCounters Link::counters() const {
  LinkCounters c = impl_->counters;
  c.wire_bytes_sent += impl_->host->totalSentData;
  c.wire_bytes_received += impl_->host->totalReceivedData;
  if (impl_->peer != nullptr) {
    c.enet_rtt_ms = impl_->peer->roundTripTime;
    c.enet_loss = static_cast<double>(impl_->peer->packetLoss) / static_cast<double>(static_cast<int>(ENET_PEER_PACKET_LOSS_SCALE));
  }
  return c;
}

ClockEstimate Link::clock() const { return impl_->estimator.estimate(); }
const ClockEstimator& Link::clock_estimator() const { return impl_->estimator; }

#else  // without ENet

namespace {
constexpr const char* kNotBuilt =
    "this curvlab is built without ENet, so it cannot play shared games: install ENet "
    "(Debian: apt-get install libenet-dev) and build again (docs/shared_play.md, \"Building\")";
}

bool built_with_enet() { return false; }
std::string enet_description() { return "without ENet (shared play is not built in)"; }

struct Link::Impl {
  ClockEstimator estimator;
};

Link::Link(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Link::Link(Link&&) noexcept = default;
Link& Link::operator=(Link&&) noexcept = default;
Link::~Link() = default;

Result<Link> Link::listen(const std::string&, std::uint16_t, const io::Clock&, LinkOptions) {
  return Error{Error::Kind::usage, kNotBuilt};
}
Result<Link> Link::join(const std::string&, std::uint16_t, const io::Clock&, LinkOptions) {
  return Error{Error::Kind::usage, kNotBuilt};
}
bool Link::connected() const { return false; }
std::uint16_t Link::port() const { return 0; }
void Link::reconnect() {}
bool Link::send(const Message&) { return false; }
void Link::flush() {}
Poll Link::poll(int) { return {}; }
void Link::wait_readable(int) const {}
void Link::close(const Bye&, int) {}
LinkCounters Link::counters() const { return {}; }
ClockEstimate Link::clock() const { return {}; }
const ClockEstimator& Link::clock_estimator() const { return impl_->estimator; }

#endif

}  // namespace curvlab::harness::net
