// The Khronos core validation API layer (XR_APILAYER_LUNARG_core_validation)
// for a program a test runs: the environment that enables it and sends its
// reports to a file, and the reports read back. The layer writes the file
// only when it has something to report, so "no file" is "no message".
// Owns nothing but the file's path; not thread-safe.
#pragma once

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

namespace curvlab::testing {

class CoreValidation {
 public:
  explicit CoreValidation(std::filesystem::path file) : file_(std::move(file)) {
    std::filesystem::remove(file_);
  }

  // XR_CORE_VALIDATION_EXPORT_TYPE and XR_CORE_VALIDATION_FILE_NAME are the
  // layer's own settings (README_core_validation.md in the package).
  [[nodiscard]] std::map<std::string, std::string> environment() const {
    std::map<std::string, std::string> vars = {{"XR_ENABLE_API_LAYERS", "XR_APILAYER_LUNARG_core_validation"},
                                               {"XR_CORE_VALIDATION_EXPORT_TYPE", "text"},
                                               {"XR_CORE_VALIDATION_FILE_NAME", file_.string()}};
    if (!std::string(CURVLAB_CORE_VALIDATION_LAYER_DIR).empty())
      vars["XR_API_LAYER_PATH"] = CURVLAB_CORE_VALIDATION_LAYER_DIR;
    return vars;
  }

  // Everything the layer reported; empty when it reported nothing.
  [[nodiscard]] std::string messages() const {
    std::ifstream in(file_);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

 private:
  std::filesystem::path file_;
};

// Program output without the line the layer prints to stdout when it starts
// ("Core Validation output type: text, first time = true"), which is not a
// report.
inline std::string without_layer_banner(const std::string& out) {
  std::istringstream in(out);
  std::string kept;
  for (std::string line; std::getline(in, line);)
    if (line.rfind("Core Validation output type:", 0) != 0) kept += line + "\n";
  return kept;
}

}  // namespace curvlab::testing
