// Whether a capture's validation checked anything of this protocol: "nothing checked is not a
// pass" (INTERFACES.md, exit status 4).
#pragma once

#include <string>
#include <vector>

#include "ncservo/validator.hpp"

namespace ncservo {

struct Coverage {
  bool any_axis = false;             // some servo axis was decoded
  std::vector<std::string> missing;  // configured axes (config, ENI) that never appeared
  std::string reason;                // why not everything was checked; empty when it was

  bool complete() const { return any_axis && missing.empty(); }
};

// After the capture's last frame.
Coverage coverageOf(const Validator& validator);

}  // namespace ncservo
