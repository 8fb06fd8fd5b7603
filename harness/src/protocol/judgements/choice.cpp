// `type = "choice"`: n-alternative forced choice. The participant presses the
// key or button of one option; every cell is repeated as the block says. The
// base class's behaviour is this type's (judgement.hpp).
#include "judgement_format.hpp"

namespace curvlab::harness::protocol {

namespace {

class Choice final : public JudgementType {
 public:
  [[nodiscard]] std::string_view name() const override { return "choice"; }
  [[nodiscard]] std::string_view summary() const override { return "n-alternative choice"; }

  void fields(JudgementFields& out) const override {
    out.add_options();
    out.require({"options"});
  }

  void read(JudgementSection& section, Judgement& out) const override { out.options = section.options(); }
};

}  // namespace

const JudgementType& choice_judgement_type() {
  static const Choice type;
  return type;
}

}  // namespace curvlab::harness::protocol
