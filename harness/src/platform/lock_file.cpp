// What LockFile does the same on every platform; opening, closing and the
// locks themselves are in posix.cpp and windows.cpp.
#include "curvlab/harness/platform/lock_file.hpp"

#include <utility>

namespace curvlab::platform {

LockFile::LockFile(LockFile&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), error_(std::exchange(other.error_, 0)), own_(std::move(other.own_)) {}

LockFile& LockFile::operator=(LockFile&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = std::exchange(other.fd_, -1);
    error_ = std::exchange(other.error_, 0);
    own_ = std::move(other.own_);
  }
  return *this;
}

LockFile::~LockFile() { close(); }

}  // namespace curvlab::platform
