// Small builders for the protocol's JSON Schema (schema.cpp), shared with the
// judgement types that declare their own keys (judgements/). Internal to
// curvlab_protocol. Pure; thread-safe.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace curvlab::harness::protocol::schema_json {

using Json = nlohmann::ordered_json;

inline constexpr const char* kIdentifierPattern = "^[a-z_][a-z0-9_-]{0,63}$";

inline Json strings(const std::vector<std::string>& items) {
  Json a = Json::array();
  for (const auto& s : items) a.push_back(s);
  return a;
}

inline Json integer(std::int64_t lo, std::int64_t hi, std::string description) {
  return {{"type", "integer"}, {"minimum", lo}, {"maximum", hi}, {"description", std::move(description)}};
}

inline Json with_default(Json j, Json value) {
  j["default"] = std::move(value);
  return j;
}

inline Json string_field(std::string description) {
  return {{"type", "string"}, {"description", std::move(description)}};
}

inline Json enum_field(const std::vector<std::string>& values, std::string description) {
  return {{"type", "string"}, {"enum", strings(values)}, {"description", std::move(description)}};
}

inline Json string_array(std::string description, const std::vector<std::string>* names = nullptr) {
  Json items = {{"type", "string"}};
  if (names) items["enum"] = strings(*names);
  return {{"type", "array"}, {"items", items}, {"description", std::move(description)}};
}

inline Json closed_object(Json properties, std::string description) {
  return {{"type", "object"},
          {"description", std::move(description)},
          {"properties", std::move(properties)},
          {"additionalProperties", false}};
}

}  // namespace curvlab::harness::protocol::schema_json
