#include "curvlab/harness/numbered_files.hpp"

#include <algorithm>
#include <cctype>
#include <system_error>

namespace curvlab::harness {

namespace {

bool used(const std::filesystem::path& dir, const std::string& stem) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(stem, 0) != 0) continue;
    if (name.size() == stem.size() || name[stem.size()] == '_' || name[stem.size()] == '.') return true;
  }
  return false;
}

}  // namespace

std::string unused_stem(const std::filesystem::path& dir, const std::string& stem) {
  if (!used(dir, stem)) return stem;
  for (int n = 2;; ++n)
    if (const std::string s = stem + "_" + std::to_string(n); !used(dir, s)) return s;
}

int highest_number(const std::filesystem::path& dir, const std::string& prefix) {
  int highest = 0;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    std::size_t end = prefix.size();
    while (end < name.size() && end - prefix.size() < 9 && std::isdigit(static_cast<unsigned char>(name[end]))) ++end;
    if (end > prefix.size()) highest = std::max(highest, std::stoi(name.substr(prefix.size(), end - prefix.size())));
  }
  return highest;
}

}  // namespace curvlab::harness
