// How long loading, validating and expanding each shipped protocol takes: the
// runner does all three at session start, before the first frame.
//   bench_protocol_load [PROTOCOL_DIR]   (default: the source tree's protocols/)
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/loader.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

namespace fs = std::filesystem;
using namespace curvlab::harness::protocol;
using Clock = std::chrono::steady_clock;

namespace {

template <typename F>
double median_us(int reps, F&& f) {
  std::vector<double> t;
  t.reserve(static_cast<std::size_t>(reps));
  for (int i = 0; i < reps; ++i) {
    const auto a = Clock::now();
    f();
    const auto b = Clock::now();
    t.push_back(std::chrono::duration<double, std::micro>(b - a).count());
  }
  std::nth_element(t.begin(), t.begin() + reps / 2, t.end());
  return t[static_cast<std::size_t>(reps / 2)];
}

}  // namespace

int main(int argc, char** argv) {
  const fs::path dir = argc > 1 ? fs::path(argv[1]) : fs::path(CURVLAB_SOURCE_DIR) / "protocols";
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".toml") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::printf("%-26s %7s %8s %12s %12s %12s\n", "protocol", "bytes", "trials", "load_us", "expand_us",
              "us/trial");
  for (const auto& f : files) {
    std::ifstream in(f);
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    const auto first = load_protocol_text(text, f.string());
    if (!first) {
      std::printf("%-26s does not validate\n", f.filename().c_str());
      continue;
    }
    const int reps = 51;
    std::size_t trials = 0;
    const double load = median_us(reps, [&] { trials += load_protocol_text(text, f.string()).has_value() ? 0 : 1; });
    const double expand = median_us(reps, [&] { trials = expand_design(*first, 7).trials.size(); });
    std::printf("%-26s %7zu %8zu %12.1f %12.1f %12.3f\n", f.filename().c_str(), text.size(), trials, load,
                expand, expand / static_cast<double>(std::max<std::size_t>(trials, 1)));
  }
  return 0;
}
