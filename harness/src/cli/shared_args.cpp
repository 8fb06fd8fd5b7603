#include "shared_args.hpp"

#include "curvlab/harness/net/link.hpp"

#include <charconv>
#include <cmath>

namespace curvlab::harness::cli {

namespace rn = curvlab::harness::runner;
namespace net = curvlab::harness::net;

void add_shared_options(CLI::App* cmd, SharedArgs& a) {
  cmd->add_option("--shared", a.role, "play the play blocks with a partner station: host or join (docs/shared_play.md)");
  cmd->add_option("--listen", a.listen, "--shared host: the UDP port to listen on for the partner");
  cmd->add_option("--partner", a.partner, "--shared join: the host station's HOST:PORT");
  cmd->add_option("--bind", a.bind, "--shared host: the address to listen on (default 0.0.0.0, every interface)");
  cmd->add_option("--initials", a.initials, "shown on this station's avatar at the partner (default: the participant's first two characters)");
  cmd->add_option("--partner-wait-s", a.wait_s, "how long to wait for the partner station (default 60 s)");
  cmd->add_option("--avatar", a.avatar, "a PNG photo of this player, drawn on its avatar's face at the partner (default: the initials)");
}

void check_shared_args(const SharedArgs& a, const harness::protocol::Protocol& p, const BackendArgs& backend) {
  const bool any = !a.role.empty() || !a.listen.empty() || !a.partner.empty();
  if (!any) return;
  if (a.role != "host" && a.role != "join")
    throw UsageError("--shared must be host or join (with --listen PORT or --partner HOST:PORT)");
  if (!net::built_with_enet()) throw UsageError("--shared: " + net::enet_description() + "; docs/shared_play.md, \"Building\"");
  if (a.role == "host" && a.listen.empty()) throw UsageError("--shared host needs --listen PORT");
  if (a.role == "join" && a.partner.empty()) throw UsageError("--shared join needs --partner HOST:PORT");
  if (a.role == "host" && !a.partner.empty()) throw UsageError("--partner is for --shared join; the host listens (--listen)");
  if (a.role == "join" && !a.listen.empty()) throw UsageError("--listen is for --shared host; the joiner names --partner");
  if (!(a.wait_s > 0.0 && a.wait_s <= 3600.0)) throw UsageError("--partner-wait-s must lie in (0, 3600] seconds");
  if (a.initials.size() > 8) throw UsageError("--initials: at most 8 characters");
  bool play = false;
  for (const auto& b : p.blocks) play = play || b.kind == "play";
  if (!play) throw UsageError("--shared: " + p.file + " has no play block to share");
  if (backend.backend == "headless" && backend.pace == "fast")
    throw UsageError("--shared needs a session in real time: add --pace realtime (a fast headless run's clock is simulated)");
}

std::unique_ptr<rn::SharedPlay> open_shared(const SharedArgs& a, const std::string& participant,
                                            const harness::protocol::Protocol& p, const std::string& protocol_text,
                                            const harness::io::Clock& clock, const std::atomic<int>* stop_signal) {
  if (a.role.empty()) return nullptr;
  rn::SharedOptions o;
  o.role = a.role == "host" ? net::Role::host : net::Role::join;
  o.bind_address = a.bind;
  o.initials = a.initials.empty() ? participant.substr(0, 2) : a.initials;
  o.wait_ns = static_cast<std::int64_t>(std::llround(a.wait_s * 1e9));
  if (!a.avatar.empty()) {
    auto photo = rn::avatar_from_png(a.avatar);
    if (!photo) throw UsageError(photo.error().message);
    o.avatar = std::move(photo).value();
  }
  if (o.role == net::Role::host) {
    unsigned port = 0;
    const auto [end, ec] = std::from_chars(a.listen.data(), a.listen.data() + a.listen.size(), port);
    if (ec != std::errc{} || end != a.listen.data() + a.listen.size() || port == 0 || port > 65535)
      throw UsageError("--listen: the port must be 1 to 65535, got '" + a.listen + "'");
    o.port = static_cast<std::uint16_t>(port);
  } else {
    auto address = net::Link::parse_address(a.partner);
    if (!address) throw UsageError(address.error().message);
    o.partner_host = address->first;
    o.port = address->second;
  }
  auto shared = rn::connect_partner(o, p, protocol_text, clock, stop_signal);
  if (!shared) raise(shared.error());
  return std::move(shared).value();
}

void close_shared(rn::SharedPlay* shared, bool completed) {
  if (shared == nullptr || !shared->link) return;
  shared->close(completed ? net::Bye{net::Bye::Reason::done, "the session ended"}
                                : net::Bye{net::Bye::Reason::quitting, "the session was interrupted"},
                      1000);
}

}  // namespace curvlab::harness::cli
