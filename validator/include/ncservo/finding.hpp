// A finding: one violation of a rule (RULES.md), reported on one frame.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "ncservo/rules.hpp"

namespace ncservo {

// Where something was seen: Wireshark's 1-based frame number and the capture time.
struct Stamp {
  std::uint64_t frame = 0;
  std::int64_t time_ns = 0;  // absolute capture time
};

struct Finding {
  RuleId rule{};
  Severity severity{};
  std::optional<std::uint16_t> axis;  // none for a finding about the bus
  Stamp at;                           // the frame it is reported on
  Stamp since;                        // where the condition began
  std::string message;                // what was seen, and what was expected
};

}  // namespace ncservo
