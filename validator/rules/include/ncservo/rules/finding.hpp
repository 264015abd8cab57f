// A finding: one violation of a rule (docs/rules.md), reported on one frame.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "ncservo/base/stamp.hpp"
#include "ncservo/rules/rules.hpp"

namespace ncservo {

struct Finding {
  RuleId rule{};
  Severity severity{};
  std::optional<std::uint16_t> axis;  // none for a finding about the bus
  Stamp at;                           // the frame it is reported on
  Stamp since;                        // where the condition began
  std::string message;                // what was seen, and what was expected
  // Its number among its rule's findings on its axis (or the bus) in its capture segment, from 1:
  // with the rule and the axis, what a baseline matches it by (docs/baselines.md).
  std::uint32_t ordinal = 0;
};

// Whether a finding stands whatever layout the learning window decides: the rules on the slaves'
// state machines and registers read no process data (docs/layout.md).
inline bool standsWithoutLayout(const Finding& finding) {
  return ruleDef(finding.rule).kind == RuleKind::Slave;
}

}  // namespace ncservo
