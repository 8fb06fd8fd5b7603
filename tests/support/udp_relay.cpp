#include "udp_relay.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <queue>
#include <random>
#include <vector>

namespace curvlab::test {
namespace {

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

sockaddr_in loopback(std::uint16_t port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return a;
}

struct Held {
  std::int64_t due_ns;
  std::uint64_t order;
  bool to_host;
  std::vector<char> bytes;
  bool operator>(const Held& o) const { return due_ns != o.due_ns ? due_ns > o.due_ns : order > o.order; }
};

}  // namespace

std::unique_ptr<UdpRelay> UdpRelay::start(const RelayOptions& options, std::string* error) {
  std::unique_ptr<UdpRelay> r(new UdpRelay());
  r->options_ = options;
  r->front_ = ::socket(AF_INET, SOCK_DGRAM, 0);
  r->back_ = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in front = loopback(options.listen_port);
  sockaddr_in target = loopback(options.target_port);
  if (r->front_ < 0 || r->back_ < 0 ||
      ::bind(r->front_, reinterpret_cast<sockaddr*>(&front), sizeof front) != 0 ||
      ::connect(r->back_, reinterpret_cast<sockaddr*>(&target), sizeof target) != 0) {
    if (error) *error = std::string("udp relay: ") + std::strerror(errno);
    return nullptr;
  }
  socklen_t len = sizeof front;
  ::getsockname(r->front_, reinterpret_cast<sockaddr*>(&front), &len);
  r->port_ = ntohs(front.sin_port);
  r->thread_ = std::thread([p = r.get()] { p->run(); });
  return r;
}

UdpRelay::~UdpRelay() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (front_ >= 0) ::close(front_);
  if (back_ >= 0) ::close(back_);
}

RelayCounters UdpRelay::counters() const { return {forwarded_.load(), dropped_.load(), reordered_.load()}; }

void UdpRelay::run() {
  std::mt19937_64 rng(options_.seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::priority_queue<Held, std::vector<Held>, std::greater<>> held;
  std::uint64_t order = 0;
  sockaddr_in joiner{};
  bool have_joiner = false;
  std::vector<char> buf(65536);

  auto admit = [&](bool to_host, const char* data, std::size_t n) {
    if (u01(rng) < options_.loss) {
      ++dropped_;
      return;
    }
    std::int64_t delay = options_.delay_ns + static_cast<std::int64_t>(u01(rng) * static_cast<double>(options_.jitter_ns));
    if (!to_host) delay += options_.extra_delay_to_joiner_ns;
    if (u01(rng) < options_.reorder) {
      delay += 2 * options_.jitter_ns + 5'000'000;
      ++reordered_;
    }
    held.push({now_ns() + delay, order++, to_host, std::vector<char>(data, data + n)});
  };

  while (!stop_) {
    const std::int64_t now = now_ns();
    while (!held.empty() && held.top().due_ns <= now) {
      const Held& h = held.top();
      if (h.to_host) {
        ::send(back_, h.bytes.data(), h.bytes.size(), 0);
      } else if (have_joiner) {
        ::sendto(front_, h.bytes.data(), h.bytes.size(), 0, reinterpret_cast<const sockaddr*>(&joiner),
                 sizeof joiner);
      }
      ++forwarded_;
      held.pop();
    }
    int wait_ms = 5;
    if (!held.empty()) {
      const std::int64_t until = (held.top().due_ns - now_ns()) / 1'000'000;
      wait_ms = static_cast<int>(std::clamp<std::int64_t>(until, 0, 5));
    }
    pollfd fds[2] = {{front_, POLLIN, 0}, {back_, POLLIN, 0}};
    if (::poll(fds, 2, wait_ms) <= 0) continue;
    if (fds[0].revents & POLLIN) {
      sockaddr_in from{};
      socklen_t len = sizeof from;
      const auto n = ::recvfrom(front_, buf.data(), buf.size(), 0, reinterpret_cast<sockaddr*>(&from), &len);
      if (n >= 0) {
        joiner = from;
        have_joiner = true;
        admit(true, buf.data(), static_cast<std::size_t>(n));
      }
    }
    if (fds[1].revents & POLLIN) {
      const auto n = ::recv(back_, buf.data(), buf.size(), 0);
      if (n >= 0) admit(false, buf.data(), static_cast<std::size_t>(n));
    }
  }
}

}  // namespace curvlab::test
