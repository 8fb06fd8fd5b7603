// Enumerations known by name in protocols, on the command line and in stored
// data. Each keeps its names in one place, the exhaustive switch of its
// to_string (a value without a name does not compile), and lists every value
// once beside its declaration; parsing and the choices offered to a protocol
// or an option are derived from those two here, so no layer spells the names
// again.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::geometry {

// The value among `values` whose to_string is `name`; nullopt for none.
template <class E, std::size_t N>
constexpr std::optional<E> parse_name(const std::array<E, N>& values, std::string_view name) {
  for (const E value : values)
    if (to_string(value) == name) return value;
  return std::nullopt;
}

// The names of `values`, in their order.
template <class E, std::size_t N>
std::vector<std::string_view> names_of(const std::array<E, N>& values) {
  std::vector<std::string_view> out;
  for (const E value : values) out.emplace_back(to_string(value));
  return out;
}

// Names as a message lists what was expected: "a, b or c".
inline std::string alternatives_text(const std::vector<std::string_view>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += i + 1 == names.size() ? " or " : ", ";
    out += names[i];
  }
  return out;
}
template <class E, std::size_t N>
std::string alternatives_text(const std::array<E, N>& values) {
  return alternatives_text(names_of(values));
}

}  // namespace curvlab::geometry
