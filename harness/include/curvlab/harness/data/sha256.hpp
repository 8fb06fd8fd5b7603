// SHA-256 (FIPS 180-4) as 64 lowercase hex digits: of protocol texts stored
// with each session, and of a session's rows (curvlab merge).
#pragma once

#include <memory>
#include <string>
#include <string_view>

namespace curvlab::harness::data {

// Incremental: add() any number of byte strings, then hex() once.
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  Sha256& add(std::string_view bytes);
  std::string hex();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

std::string sha256_hex(std::string_view bytes);

}  // namespace curvlab::harness::data
