// The judgement types, registered in the order users see them: the `type`
// values the loader lists, the schema's alternatives, the docs' sections.
// Each type's file (judgements/<name>.cpp) defines its function.
#include "curvlab/harness/protocol/judgement.hpp"

namespace curvlab::harness::protocol {

const JudgementType& choice_judgement_type();
const JudgementType& adjustment_judgement_type();
const JudgementType& staircase_judgement_type();
const JudgementType& psi_judgement_type();

const std::vector<const JudgementType*>& judgement_types() {
  static const std::vector<const JudgementType*> types{
      &choice_judgement_type(),
      &adjustment_judgement_type(),
      &staircase_judgement_type(),
      &psi_judgement_type(),
  };
  return types;
}

}  // namespace curvlab::harness::protocol
