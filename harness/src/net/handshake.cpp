#include <curvlab/harness/net/handshake.hpp>

#include <algorithm>
#include <map>

#include <curvlab/harness/data/sha256.hpp>

namespace curvlab::harness::net {
namespace {

bool is_zero(const Uuid& u) {
  return std::all_of(u.begin(), u.end(), [](std::uint8_t b) { return b == 0; });
}

std::string short_hash(const std::string& h) { return h.substr(0, 12); }

void add(std::string& out, const std::string& sentence) {
  if (!out.empty()) out += ' ';
  out += sentence;
}

}  // namespace

std::string canonical_parameters(Parameters params) {
  std::sort(params.begin(), params.end());
  std::string text;
  for (const auto& [k, v] : params) {
    text += k;
    text += '=';
    text += v;
    text += '\n';
  }
  return text;
}

Hello make_hello(Role role, std::string software_version, std::string protocol_sha256, Parameters params,
                 std::string initials) {
  Hello h;
  h.role = role;
  h.software_version = std::move(software_version);
  h.protocol_sha256 = std::move(protocol_sha256);
  h.parameters_sha256 = data::sha256_hex(canonical_parameters(params));
  std::sort(params.begin(), params.end());
  h.parameters = std::move(params);
  h.initials = std::move(initials);
  return h;
}

std::optional<std::string> incompatibility(const Hello& mine, const Hello& theirs) {
  std::string out;
  if (mine.role == theirs.role) {
    std::string s = "Both stations are ";
    s += mine.role == Role::host ? "hosts" : "joiners";
    s += ": one must be [shared] role = \"host\", the other \"join\".";
    add(out, s);
  }
  if (mine.software_version != theirs.software_version) {
    std::string s = "The curvlab versions differ: this station runs ";
    s += mine.software_version;
    s += ", the partner ";
    s += theirs.software_version;
    s += "; install the same version on both.";
    add(out, s);
  }
  if (mine.protocol_sha256 != theirs.protocol_sha256) {
    std::string s = "The protocols differ: this station's protocol has SHA-256 ";
    s += short_hash(mine.protocol_sha256);
    s += "..., the partner's ";
    s += short_hash(theirs.protocol_sha256);
    s += "...; copy the same protocol file to both stations.";
    add(out, s);
  }
  if (mine.parameters_sha256 != theirs.parameters_sha256) {
    std::map<std::string, std::string> a(mine.parameters.begin(), mine.parameters.end());
    std::map<std::string, std::string> b(theirs.parameters.begin(), theirs.parameters.end());
    std::vector<std::string> named;
    for (const auto& [k, v] : a) {
      auto it = b.find(k);
      std::string s = k;
      s += ": this station ";
      s += v;
      s += ", the partner ";
      s += it == b.end() ? std::string("(none)") : it->second;
      if (it == b.end() || it->second != v) named.push_back(std::move(s));
    }
    for (const auto& [k, v] : b) {
      if (a.count(k)) continue;
      std::string s = k;
      s += ": this station (none), the partner ";
      s += v;
      named.push_back(std::move(s));
    }
    std::string s = "The game's parameters differ";
    if (named.empty()) {
      s += " (their digests differ).";
    } else {
      s += " (";
      for (std::size_t i = 0; i < named.size(); ++i) {
        if (i) s += "; ";
        s += named[i];
      }
      s += ").";
    }
    add(out, s);
  }
  if (!is_zero(mine.game_uuid) && !is_zero(theirs.game_uuid) && mine.game_uuid != theirs.game_uuid)
    add(out, "The stations were in different games: resume each session with its own partner.");
  if (out.empty()) return std::nullopt;
  return out;
}

}  // namespace curvlab::harness::net
