// The head of a small protocol at one table: a 1 m table in H3 (radius from
// the table), table-anchored tracking, and a two-option choice judgement
// answered by keys 1 and 2 or, where named, two controller buttons. The
// caller appends its blocks.
#pragma once

#include <string>

namespace curvlab::test {

inline std::string table_protocol_head(const std::string& name, const std::string& button_a = "",
                                       const std::string& button_b = "") {
  auto option = [](const char* value, const char* key, const std::string& button) {
    return std::string("[[judgement.options]]\nvalue = \"") + value + "\"\nkeys = [\"" + key + "\"]\n" +
           (button.empty() ? "" : "buttons = [\"" + button + "\"]\n");
  };
  return "[protocol]\nname = \"" + name +
         "\"\nversion = \"1.0.0\"\n"
         "[randomization]\nseed = 1\n[table]\nedge_m = 1.0\n"
         "[space]\nkind = \"H3\"\nradius_m = \"from_table\"\n"
         "[tracking]\nalgorithm = \"table-anchored\"\n"
         "[judgement]\ntype = \"choice\"\nprompt = \"?\"\n" +
         option("a", "1", button_a) + option("b", "2", button_b);
}

}  // namespace curvlab::test
