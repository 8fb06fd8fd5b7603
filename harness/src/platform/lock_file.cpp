// What LockFile does the same on every platform; opening, closing and the
// locks themselves are in posix.cpp and windows.cpp.
#include "curvlab/harness/platform/lock_file.hpp"

#include <utility>

namespace curvlab::harness::platform {

std::string describe(Unsafe why) {
  switch (why) {
    case Unsafe::none: return "nothing";
    case Unsafe::link: return "is a symbolic link (or a reparse point)";
    case Unsafe::not_regular: return "is not a regular file";
    case Unsafe::several_names: return "is a hard link: another name reaches the same file";
    case Unsafe::other_owner: return "belongs to another user";
  }
  return "is not a file curvlab made";
}

LockFile::LockFile(LockFile&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      error_(std::exchange(other.error_, 0)),
      unsafe_(std::exchange(other.unsafe_, Unsafe::none)),
      keep_open_(std::exchange(other.keep_open_, false)),
      own_(std::move(other.own_)) {}

LockFile& LockFile::operator=(LockFile&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = std::exchange(other.fd_, -1);
    error_ = std::exchange(other.error_, 0);
    unsafe_ = std::exchange(other.unsafe_, Unsafe::none);
    keep_open_ = std::exchange(other.keep_open_, false);
    own_ = std::move(other.own_);
  }
  return *this;
}

LockFile::~LockFile() { close(); }

}  // namespace curvlab::harness::platform
