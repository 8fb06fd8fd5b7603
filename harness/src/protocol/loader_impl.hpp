// The protocol loader's one pass over a parsed file (loader.hpp): the class
// that walks the TOML document, private to the protocol folder. Its parts
// are split by what they read: the top level and settings (loader.cpp),
// factors, judgements, blocks and counterbalancing (loader_blocks.cpp), and
// the checks of the design as a whole (loader_checks.cpp).
//
// One Loader reads one file, on one thread.
#pragma once

#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/latin_square.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "judgements/judgement_format.hpp"
#include "table_reader.hpp"

#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::protocol {

class Loader : private TableReader {
 public:
  explicit Loader(std::string file) : TableReader(std::move(file)) {}

  Result<Protocol> run(std::string_view text);

 private:
  // ---- settings sections (session level and per block) ----------------
  void read_settings(const toml::table& t, const std::string& prefix, std::vector<SettingOverride>& out);

  // ---- top level ---------------------------------------------------------
  void read_root(const toml::table& root, Protocol& p);
  void read_metadata(const toml::table& root, Protocol& p);
  void read_backend(const toml::table& root, Protocol& p);
  void read_calibration(const toml::table& root, Protocol& p);
  void read_randomization(const toml::table& root, Protocol& p);
  static RandomizeMode parse_mode(const std::string& m);
  void read_factors(const toml::table& root, Protocol& p);

  // ---- judgements -------------------------------------------------------
  // The common keys here; the rest is the type's (judgement.hpp).
  Judgement read_judgement(const toml::table& j, const std::string& prefix, const Protocol& p);

  // ---- blocks ------------------------------------------------------------
  void read_blocks(const toml::table& root, Protocol& p);
  void read_play(const toml::table& t, const std::string& bp, Block& b);
  // ---- questionnaires (loader_questionnaires.cpp) --------------------------
  void read_instruments(const toml::table& root, Protocol& p);
  void read_scale(const toml::table& t, const std::string& prefix, Instrument& ins);
  void read_items(const toml::table& t, const std::string& prefix, Instrument& ins);
  void read_subscales(const toml::table& t, const std::string& prefix, Instrument& ins);
  void read_questionnaire(const toml::table& t, const std::string& bp, const Protocol& p, Block& b);
  void read_block_levels(const toml::table& lv, const std::string& prefix, const Protocol& p, Block& b);
  void read_counterbalance(const toml::table& root, Protocol& p);

  // ---- the design as a whole ---------------------------------------------
  void check_design(const Protocol& p, const toml::table& root);

  // Resolves every factor-level combination of a block and checks what can
  // only be checked on the combination (a table that cannot exist in a space,
  // a bend deeper than the stick allows).
  void check_cells(const Protocol& p, const Block& b, const std::string& bp);

  // Checks that need a whole resolved set of settings.
  template <typename Report>
  static void check_settings(const Settings& s, const Report& report);

  RandomizeMode default_randomize_ = RandomizeMode::shuffle;
  bool has_root_judgement_ = false;
  // Factor → labels of its levels that were reported and left out; a block
  // naming one gets no second error.
  std::map<std::string, std::set<std::string>> rejected_levels_;
};

}  // namespace curvlab::harness::protocol
