#include "curvlab/harness/runner/shared_play.hpp"

#include "curvlab/harness/data/sha256.hpp"
#include "curvlab/harness/data/uuid.hpp"
#include "curvlab/harness/render_result.hpp"
#include "curvlab/harness/version.hpp"
#include "curvlab/renderer/colour.hpp"
#include "curvlab/renderer/image_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace curvlab::harness::runner {
namespace {

std::string number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

net::Uuid parse_uuid(const std::string& text) {
  net::Uuid u{};
  std::size_t k = 0;
  for (std::size_t i = 0; i + 1 < text.size() && k < u.size();) {
    if (text[i] == '-') {
      ++i;
      continue;
    }
    u[k++] = static_cast<std::uint8_t>(std::stoi(text.substr(i, 2), nullptr, 16));
    i += 2;
  }
  return u;
}

}  // namespace

SharedPlay::~SharedPlay() { stop_service(); }

void SharedPlay::start_service() {
  if (thread_.joinable() || !link) return;
  stop_ = false;
  thread_ = std::thread([this] { serve(); });
}

void SharedPlay::stop_service() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void SharedPlay::serve() {
  while (!stop_) {
    link->wait_readable(2);
    std::lock_guard lock(mutex_);
    net::Poll p = link->poll(0);
    inbox_.connected = inbox_.connected || p.connected;
    inbox_.disconnected = inbox_.disconnected || p.disconnected;
    for (auto& r : p.messages) {
      if (std::holds_alternative<net::PoseFrame>(r.message) && ++poses_waiting_ > 256) {
        // The oldest pose frame waiting gives way (the frame thread is held up).
        for (auto it = inbox_.messages.begin(); it != inbox_.messages.end(); ++it)
          if (std::holds_alternative<net::PoseFrame>(it->message)) {
            inbox_.messages.erase(it);
            --poses_waiting_;
            break;
          }
      }
      inbox_.messages.push_back(std::move(r));
    }
  }
}

net::Poll SharedPlay::take() {
  std::lock_guard lock(mutex_);
  if (!thread_.joinable()) return link->poll(0);
  net::Poll out = std::move(inbox_);
  inbox_ = {};
  poses_waiting_ = 0;
  return out;
}

bool SharedPlay::send(const net::Message& m) {
  std::lock_guard lock(mutex_);
  return link->send(m);
}
void SharedPlay::flush() {
  std::lock_guard lock(mutex_);
  link->flush();
}
bool SharedPlay::connected() {
  std::lock_guard lock(mutex_);
  return link->connected();
}
void SharedPlay::reconnect() {
  std::lock_guard lock(mutex_);
  link->reconnect();
}
net::ClockEstimate SharedPlay::clock() {
  std::lock_guard lock(mutex_);
  return link->clock();
}
std::int64_t SharedPlay::to_local_ns(std::int64_t partner_ns) {
  std::lock_guard lock(mutex_);
  return link->clock_estimator().to_local_ns(partner_ns);
}
net::LinkCounters SharedPlay::counters() {
  std::lock_guard lock(mutex_);
  return link->counters();
}
void SharedPlay::close(const net::Bye& bye, int timeout_ms) {
  stop_service();
  if (link) link->close(bye, timeout_ms);
}

Result<net::Avatar> avatar_from_png(const std::string& path) {
  auto read = from_renderer(renderer::read_png(path), "--avatar: ");
  if (!read) return Error{Error::Kind::usage, read.error().message};
  const renderer::Rgba8Image& image = read.value();
  if (image.width < 1 || image.height < 1) return Error{Error::Kind::usage, "--avatar: " + path + " has no pixels"};
  // Whole source pixels per avatar pixel: the smallest step that fits.
  const int side = static_cast<int>(net::kMaxAvatarSide);
  const int step = std::max((image.width + side - 1) / side, (image.height + side - 1) / side);
  net::Avatar a;
  a.width = static_cast<std::uint16_t>(image.width / step);
  a.height = static_cast<std::uint16_t>(image.height / step);
  if (a.width == 0 || a.height == 0)
    return Error{Error::Kind::usage, "--avatar: " + path + " is too thin to draw (" + std::to_string(image.width) +
                                         " × " + std::to_string(image.height) + " pixels)"};
  a.grey.resize(std::size_t{a.width} * a.height);
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      double sum = 0.0;
      for (int dy = 0; dy < step; ++dy)
        for (int dx = 0; dx < step; ++dx) {
          const std::uint8_t* p = &image.pixels[4 * (static_cast<std::size_t>(y * step + dy) * image.width + x * step + dx)];
          // Rec. 709 luma of the encoded values, over white by its alpha.
          const double luma = renderer::relative_luminance(glm::vec3(p[0], p[1], p[2]));
          const double alpha = p[3] / 255.0;
          sum += alpha * luma + (1.0 - alpha) * 255.0;
        }
      a.grey[static_cast<std::size_t>(y) * a.width + x] =
          static_cast<std::uint8_t>(std::lround(sum / static_cast<double>(step * step)));
    }
  return a;
}

Result<renderer::CoverageBitmap> avatar_face(const std::optional<net::Avatar>& photo, const std::string& initials,
                                             const std::string& font) {
  // A card 4 wide by 5 high; a photo is centred on it at its own aspect.
  // Panels draw light ink on dark paper: the coverage is the brightness.
  constexpr int kWidth = 128, kHeight = 160;
  if (!photo) {
    auto text = from_renderer(renderer::render_text(initials.empty() ? "?" : initials, kWidth, kHeight, 64.0, font));
    if (!text) return Error{Error::Kind::device, "the partner's avatar: " + text.error().message};
    return std::move(text).value();
  }
  renderer::CoverageBitmap card{kWidth, kHeight, std::vector<std::uint8_t>(std::size_t{kWidth} * kHeight, 0)};
  const double scale = std::min(double(kWidth) / photo->width, double(kHeight) / photo->height);
  const int w = std::max(1, static_cast<int>(photo->width * scale));
  const int h = std::max(1, static_cast<int>(photo->height * scale));
  const int x0 = (kWidth - w) / 2, y0 = (kHeight - h) / 2;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int sx = std::min<int>(photo->width - 1, static_cast<int>(x / scale));
      const int sy = std::min<int>(photo->height - 1, static_cast<int>(y / scale));
      card.pixels[static_cast<std::size_t>(y0 + y) * kWidth + x0 + x] =
          photo->grey[static_cast<std::size_t>(sy) * photo->width + sx];
    }
  return card;
}

std::string uuid_text(const net::Uuid& u) {
  static constexpr char hex[] = "0123456789abcdef";
  std::string s;
  for (std::size_t i = 0; i < u.size(); ++i) {
    if (i == 4 || i == 6 || i == 8 || i == 10) s += '-';
    s += hex[u[i] >> 4];
    s += hex[u[i] & 0xf];
  }
  return s;
}

net::Parameters shared_parameters(const protocol::Protocol& p) {
  net::Parameters params;
  params.emplace_back("table.edge_m", number(p.session_settings().table.edge_m));
  for (std::size_t i = 0; i < p.blocks.size(); ++i) {
    const auto& b = p.blocks[i];
    if (b.kind != "play") continue;
    const std::string at = "play." + std::to_string(i) + ".";
    params.emplace_back(at + "shots", std::to_string(b.play.shots));
    params.emplace_back(at + "duration_s", number(b.play.duration_s));
    params.emplace_back(at + "rack", std::to_string(b.play.rack));
    params.emplace_back(at + "until_all_pocketed", b.play.until_all_pocketed ? "true" : "false");
    for (const auto& [name, value] : b.play.physics) params.emplace_back(at + "physics." + name, number(value));
  }
  return params;
}

Result<std::unique_ptr<SharedPlay>> connect_partner(const SharedOptions& options, const protocol::Protocol& p,
                                                    const std::string& protocol_text, const io::Clock& clock,
                                                    const std::atomic<int>* stop_signal) {
  auto shared = std::make_unique<SharedPlay>();
  shared->options = options;
  shared->software_version = std::string(software_version());
  auto link = options.role == net::Role::host ? net::Link::listen(options.bind_address, options.port, clock)
                                              : net::Link::join(options.partner_host, options.port, clock);
  if (!link) return link.error();
  shared->link.emplace(std::move(link).value());
  net::Link& l = *shared->link;
  shared->mine = net::make_hello(options.role, shared->software_version, data::sha256_hex(protocol_text),
                                 shared_parameters(p), options.initials);
  const std::int64_t deadline = clock.now_ns() + options.wait_ns;
  const std::string where = options.role == net::Role::host
                                ? "on port " + std::to_string(l.port())
                                : "at " + options.partner_host + ":" + std::to_string(options.port);
  auto stopped = [&] { return stop_signal != nullptr && stop_signal->load() != 0; };
  bool sent = false;
  std::optional<net::Hello> partner;
  std::optional<net::GameState> game;
  for (;;) {
    if (stopped()) return Error{Error::Kind::usage, "stopped while waiting for the partner station"};
    if (clock.now_ns() > deadline)
      return Error{Error::Kind::device, "no partner station came " + where + " within " +
                                            std::to_string(options.wait_ns / 1'000'000'000) +
                                            " s (is it started, with the same --partner port, and does the "
                                            "firewall let UDP through? docs/shared_play.md)"};
    const net::Poll poll = l.poll(10);
    if (poll.disconnected && options.role == net::Role::join) {
      sent = false;
      l.reconnect();
    }
    if (l.connected() && !sent) {
      sent = l.send(shared->mine);
      if (sent && options.avatar) l.send(*options.avatar);
    }
    for (const auto& r : poll.messages) {
      if (const auto* h = std::get_if<net::Hello>(&r.message)) partner = *h;
      if (const auto* g = std::get_if<net::GameState>(&r.message)) game = *g;
      if (const auto* a = std::get_if<net::Avatar>(&r.message)) shared->partner_avatar = *a;
      if (const auto* bye = std::get_if<net::Bye>(&r.message))
        return Error{Error::Kind::usage, "the partner station refused this one: " + bye->text};
    }
    if (!partner) continue;
    if (const auto why = net::incompatibility(shared->mine, *partner)) {
      l.close(net::Bye{net::Bye::Reason::incompatible, *why}, 1000);
      return Error{Error::Kind::usage, "the partner station differs: " + *why};
    }
    shared->partner = *partner;
    if (options.role == net::Role::host) {
      // A partner still in a game (this host was killed and resumed) names
      // it: the host rejoins that game; otherwise the host names a new one.
      const bool rejoin = std::any_of(partner->game_uuid.begin(), partner->game_uuid.end(),
                                      [](std::uint8_t b) { return b != 0; });
      shared->game_uuid = rejoin ? partner->game_uuid : parse_uuid(data::new_session_uuid());
      shared->partner_completed_shots = partner->completed_shots;
      net::GameState g;
      g.game_uuid = shared->game_uuid;
      g.phase = net::GameState::Phase::playing;
      l.send(g);
      l.flush();
      break;
    }
    if (game) {
      shared->game_uuid = game->game_uuid;
      shared->partner_completed_shots = game->completed_shots;
      break;
    }
  }
  shared->start_service();
  return shared;
}

}  // namespace curvlab::harness::runner
