#include "curvlab/harness/data/staging.hpp"

#include <cerrno>
#include <charconv>
#include <filesystem>
#include <limits>
#include <string_view>

#include "curvlab/harness/platform/lock_file.hpp"
#include "curvlab/harness/platform/process.hpp"

namespace curvlab::harness::data {

namespace fs = std::filesystem;

bool process_alive(pid_t pid) { return platform::process_alive(pid); }

std::size_t remove_stale_staging(const std::string& dir, const std::string& prefix, StagingKind kind) {
  return remove_numbered(dir, prefix, kind, [](std::int64_t pid) {
    return pid > 0 && pid <= std::numeric_limits<pid_t>::max() && !process_alive(static_cast<pid_t>(pid));
  });
}

namespace {

bool strip(std::string_view& rest, std::string_view part) {
  if (!rest.starts_with(part)) return false;
  rest.remove_prefix(part.size());
  return true;
}

// What may follow a work file's number: curvlab's own names only —
// [.sqlite][.merging-N][-wal | -shm | -journal | .lock] (a pooled export's
// copy, the merge into it, SQLite's companions and curvlab's lock file).
bool known_rest(std::string_view rest, StagingKind kind) {
  if (kind != StagingKind::database) return rest.empty();
  strip(rest, ".sqlite");
  if (strip(rest, ".merging-")) {
    const std::size_t digits = rest.find_first_not_of("0123456789");
    if (digits == 0) return false;
    rest.remove_prefix(digits == std::string_view::npos ? rest.size() : digits);
  }
  return rest.empty() || rest == "-wal" || rest == "-shm" || rest == "-journal" || rest == ".lock";
}

bool is_kind(const fs::directory_entry& entry, StagingKind kind) {
  std::error_code ec;
  const auto status = entry.symlink_status(ec);  // a link is never followed, nor removed
  return !ec && (kind == StagingKind::folder ? fs::is_directory(status) : fs::is_regular_file(status));
}

}  // namespace

std::size_t remove_numbered(const std::string& dir, const std::string& prefix, StagingKind kind,
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
    if (err != std::errc() || end == first || !known_rest(std::string_view(end, last), kind)) continue;
    if (!is_kind(entry, kind) || !stale(number)) continue;
    std::error_code remove_ec;
    const bool gone = kind == StagingKind::folder ? fs::remove_all(entry.path(), remove_ec) > 0 && !remove_ec
                                                  : platform::remove_regular_file(entry.path().string());
    if (gone) ++removed;
  }
  return removed;
}

}  // namespace curvlab::harness::data
