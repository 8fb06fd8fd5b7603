// A scripted participant for Monado's `remote` driver: it connects to the
// TCP port on which Monado (P_OVERRIDE_ACTIVE_CONFIG=remote) listens and
// streams the head, both Index controllers' grip poses and their buttons,
// so that a real OpenXR runtime hands curvlab poses and button presses that
// came from outside the application. The head, the hands and the presses are
// the scripted runtime's (tests/xr/runtime/script.hpp): the same
// CURVLAB_TEST_XR_PRESS and CURVLAB_TEST_XR_HAND variables, with times
// counted from the connection instead of from focus.
//
// The packet is Monado's `struct r_remote_data` (src/xrt/drivers/remote/
// r_interface.h in Monado 25.0.0, header "mndrmt3"): written out here field
// by field, and checked at run time against the first packet Monado sends
// on every connection (its reset state: head 1.6 m up, left hand at
// (-0.2, 1.3, -0.5), both hands active).
//
//   curvlab_monado_remote PORT [SECONDS]   stream until Monado disconnects
//                                          (or SECONDS have passed)
// Exit 0 once nothing has listened for 3 s after at least one packet was
// sent; 1 when nothing listened within 10 s or when Monado's reset packet
// does not match this layout.
#include "runtime/script.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

namespace {

using namespace curvlab::test_runtime;

struct Quatf {
  float x, y, z, w;
};
struct Vec3f {
  float x, y, z;
};
struct Posef {
  Quatf orientation;
  Vec3f position;
};
struct Fovf {
  float left, right, up, down;
};

struct Controller {
  Posef pose;
  Vec3f linear_velocity;
  Vec3f angular_velocity;
  float hand_curl[5];
  float trigger_value;
  float squeeze_value;
  float squeeze_force;
  float thumbstick[2];
  float trackpad_force;
  float trackpad[2];
  bool hand_tracking_active;
  bool active;
  bool system_click, system_touch, a_click, a_touch, b_click, b_touch;
  bool trigger_click, trigger_touch, thumbstick_click, thumbstick_touch, trackpad_touch;
  bool pad[3];
};

struct View {
  Fovf fov;
  Posef pose;
  std::uint32_t pad;
};

struct Head {
  View views[2];
  Posef center;
  bool per_view_data_valid;
  bool pad[3];
};

struct Packet {
  std::uint64_t header;
  Head head;
  Controller left, right;
};

// Sizes as r_interface.h states them in its padding comments.
static_assert(sizeof(Controller) == 120);
static_assert(sizeof(View) == 48);
static_assert(sizeof(Head) == 128);
static_assert(sizeof(Packet) == 376);
static_assert(offsetof(Packet, left) == 136);

constexpr char kHeader[8] = {'m', 'n', 'd', 'r', 'm', 't', '3', '\0'};

Posef to_float(const Pose& p) {
  return {{static_cast<float>(p.orientation.x), static_cast<float>(p.orientation.y),
           static_cast<float>(p.orientation.z), static_cast<float>(p.orientation.w)},
          {static_cast<float>(p.position_m.x), static_cast<float>(p.position_m.y),
           static_cast<float>(p.position_m.z)}};
}

// Sets the Index controller's inputs that Monado binds to `button` of the
// Touch profile curvlab suggests (Monado's vive_bindings.c: X and Y of the
// left Touch are the left Index's A and B; menu is the system button).
void press(Controller& c, const std::string& button) {
  if (button == "a" || button == "x") c.a_click = c.a_touch = true;
  if (button == "b" || button == "y") c.b_click = c.b_touch = true;
  if (button == "menu") c.system_click = true;
  if (button == "trigger") {
    c.trigger_value = 1.0F;
    c.trigger_click = c.trigger_touch = true;
  }
  if (button == "squeeze") c.squeeze_value = 1.0F;
}

Packet packet_at(const Script& script, double t_s) {
  Packet p{};
  std::memcpy(&p.header, kHeader, sizeof kHeader);
  p.head.center = to_float(head_pose(t_s));
  for (int hand = 0; hand < 2; ++hand) {
    Controller& c = hand == 0 ? p.left : p.right;
    c.pose = to_float(hand_pose(script, hand, t_s, t_s));
    c.active = true;
  }
  for (const Press& pr : script.presses)
    if (held_since(pr, t_s)) press(pr.hand == "left" ? p.left : p.right, pr.button);
  return p;
}

int connect_with_retries(int port, int attempts) {
  for (int attempt = 0; attempt < attempts; ++attempt) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) return -1;
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0) return fd;
    ::close(fd);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return -1;
}

bool read_all(int fd, void* out, std::size_t size) {
  auto* at = static_cast<char*>(out);
  while (size > 0) {
    const ssize_t n = ::recv(fd, at, size, 0);
    if (n <= 0) return false;
    at += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

// Monado's reset state, from r_create_devices (its header is left zero:
// Monado neither sets nor checks it).
bool is_monado_reset(const Packet& p) {
  auto near = [](float a, float b) { return a > b - 1e-6F && a < b + 1e-6F; };
  return near(p.head.center.position.y, 1.6F) &&
         near(p.left.pose.position.x, -0.2F) && near(p.left.pose.position.y, 1.3F) &&
         near(p.left.pose.position.z, -0.5F) && near(p.right.pose.position.x, 0.2F) && p.left.active &&
         p.right.active && p.left.hand_tracking_active;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: curvlab_monado_remote PORT [SECONDS]\n");
    return 2;
  }
  const int port = std::atoi(argv[1]);
  const double limit_s = argc > 2 ? std::atof(argv[2]) : 1e9;
  std::string error;
  const std::optional<Script> script = read_script(error);
  if (!script) {
    std::fprintf(stderr, "curvlab_monado_remote: %s\n", error.c_str());
    return 2;
  }
  // Monado's remote hub listens while an XrInstance lives; a program that
  // creates more than one (a check, then the session) is followed to the next.
  const auto start = std::chrono::steady_clock::now();
  long sent = 0;
  int connections = 0;
  for (int fd; (fd = connect_with_retries(port, connections == 0 ? 100 : 30)) >= 0;) {
    Packet reset{};
    if (!read_all(fd, &reset, sizeof reset) || !is_monado_reset(reset)) {
      std::fprintf(stderr,
                   "curvlab_monado_remote: Monado's first packet is not the reset state this layout expects\n");
      ::close(fd);
      return 1;
    }
    ++connections;
    std::printf("connected to Monado's remote driver on port %d; its reset packet matches the layout\n", port);
    std::fflush(stdout);
    for (;;) {
      const double t_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (t_s > limit_s) break;
      const Packet p = packet_at(*script, t_s);
      if (::send(fd, &p, sizeof p, MSG_NOSIGNAL) != static_cast<ssize_t>(sizeof p)) break;
      ++sent;
      std::this_thread::sleep_for(std::chrono::milliseconds(4));
    }
    ::close(fd);
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > limit_s) break;
  }
  if (connections == 0)
    std::fprintf(stderr, "curvlab_monado_remote: nothing listened on 127.0.0.1:%d within 10 s\n", port);
  std::printf("sent %ld packets over %d connection(s)\n", sent, connections);
  return sent > 0 ? 0 : 1;
}
