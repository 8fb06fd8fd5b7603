// What a judgement type reads its table with and declares its keys through
// (judgement.hpp: JudgementType::read and ::fields), and the pieces the types
// share: the answer options and the varied parameter. The loader builds a
// JudgementSection for every [judgement] table; the schema generator and the
// loader's key check collect every type's JudgementFields.
//
// Internal to curvlab_protocol: it exposes toml++ and the JSON library. Not
// thread-safe: one section per table read.
#pragma once

#include "curvlab/harness/protocol/judgement.hpp"

#include "../schema_json.hpp"
#include "../table_reader.hpp"

#include <string>
#include <utility>
#include <vector>

namespace curvlab::harness::protocol {

// One [judgement] table being read; problems go to the loader's diagnostics.
class JudgementSection {
 public:
  JudgementSection(TableReader& into, const toml::table& read, std::string field, const Protocol& so_far)
      : reader(into), table(read), prefix(std::move(field)), protocol(so_far) {}

  TableReader& reader;
  const toml::table& table;
  const std::string prefix;  // the table's dotted field: "judgement", "blocks[2].judgement"
  const Protocol& protocol;  // as read so far: its factors

  // [[prefix.options]]: at least two, values and bindings unique.
  std::vector<ResponseOption> options();
  // `parameter`: a numeric setting no factor varies; "" after saying why not.
  std::string parameter();
};

// lo < hi, inside the parameter's own range when `param` names one;
// otherwise reported at `at` (`field`) with both values, and false.
bool check_range(TableReader& reader, const std::string& param, double lo, double hi, const toml::table& at,
                 const std::string& field);

// The keys one type's table takes besides `type` and `prompt`, in order, each
// with its schema. A description says what the key is without naming the
// type: the schema generator prefixes the types that take it.
class JudgementFields {
 public:
  using Json = schema_json::Json;

  void add(std::string key, Json schema) { keys_.emplace_back(std::move(key), std::move(schema)); }
  void require(std::vector<std::string> keys) { required_ = std::move(keys); }
  // The shared keys, with the one schema every type that takes them uses.
  void add_options();
  void add_parameter();

  [[nodiscard]] const std::vector<std::pair<std::string, Json>>& keys() const { return keys_; }
  [[nodiscard]] const std::vector<std::string>& required() const { return required_; }

 private:
  std::vector<std::pair<std::string, Json>> keys_;
  std::vector<std::string> required_;
};

// A type's declared fields.
JudgementFields fields_of(const JudgementType& type);
// The keys a type's table takes: "type", "prompt", then its own.
std::vector<std::string> table_keys(const JudgementType& type);

// One key some type's table takes, with the types that take it (in
// registration order) and its schema.
struct TypeKey {
  std::string key;
  JudgementFields::Json schema;
  std::vector<const JudgementType*> types;
};
// Every type's own keys, each once: types with fewer keys first, so that a
// short type's keys are not buried under a long one's.
std::vector<TypeKey> type_keys();
// The keys any type's table takes: "type", "prompt", then type_keys().
std::vector<std::string> any_table_keys();

}  // namespace curvlab::harness::protocol
