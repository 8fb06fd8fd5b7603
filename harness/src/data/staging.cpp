#include "curvlab/harness/data/staging.hpp"

#include <cerrno>
#include <charconv>
#include <filesystem>
#include <limits>

#include "curvlab/harness/platform/process.hpp"

namespace curvlab::data {

namespace fs = std::filesystem;

bool process_alive(pid_t pid) { return platform::process_alive(pid); }

std::size_t remove_stale_staging(const std::string& dir, const std::string& prefix) {
  return remove_numbered(dir, prefix, [](std::int64_t pid) {
    return pid > 0 && pid <= std::numeric_limits<pid_t>::max() && !process_alive(static_cast<pid_t>(pid));
  });
}

std::size_t remove_numbered(const std::string& dir, const std::string& prefix,
                            const std::function<bool(std::int64_t number)>& stale) {
  std::error_code ec;
  std::size_t removed = 0;
  const fs::path folder = dir.empty() ? fs::path(".") : fs::path(dir);
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const char* first = name.data() + prefix.size();
    const char* last = name.data() + name.size();
    std::int64_t number = 0;
    const auto [end, err] = std::from_chars(first, last, number);
    if (err != std::errc() || end == first || (end != last && *end != '.' && *end != '-')) continue;
    if (!stale(number)) continue;
    std::error_code remove_ec;
    if (fs::remove_all(entry.path(), remove_ec) > 0 && !remove_ec) ++removed;
  }
  return removed;
}

}  // namespace curvlab::data
