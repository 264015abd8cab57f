// Whether a capture's validation checked anything of this protocol: "nothing checked is not a
// pass" (docs/cli.md, exit status 4).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/rules/validator.hpp"

namespace ncservo {

// A rule that could not be judged (for an axis, or on the bus) because what it reads was never
// captured, e.g. cut off by a snap length.
struct NotJudged {
  RuleId rule{};
  std::optional<std::uint16_t> axis;
  std::string reason;
};

struct Coverage {
  bool any_axis = false;              // some servo axis's PDO words were read
  std::vector<std::string> missing;   // configured axes (config, ENI) that never appeared
  std::string reason;                 // why not everything was checked, one line; empty when it was
  bool wants_layout = false;          // the reason asks for a --config file (kLayoutConfigExample)
  std::vector<NotJudged> not_judged;  // enabled rules, in axis then table order; the bus's last

  bool complete() const { return any_axis && missing.empty(); }
};

// After the capture's last frame.
Coverage coverageOf(const Validator& validator);

}  // namespace ncservo
