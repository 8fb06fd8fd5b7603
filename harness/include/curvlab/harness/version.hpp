#pragma once

#include <string_view>

namespace curvlab {

// The software version and the git commit it was built from; both are stored
// with every session (DESIGN.md §7, provenance).
std::string_view software_version();
std::string_view git_commit();

}  // namespace curvlab
