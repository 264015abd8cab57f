// `decode --axis`: the axes to show, each given by its name or its index (0-based, as "axis" in
// the reports).
#pragma once

#include <string>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/layout/decoder.hpp"

namespace ncservo::report {

// Whether `axis` is one of `wanted`; every axis is when nothing is wanted.
bool axisSelected(const std::vector<std::string>& wanted, const AxisInfo& axis);

// An error naming each entry of `wanted` that is no axis of `axes`, and the axes there are.
Status checkAxisSelection(const std::vector<std::string>& wanted,
                          const std::vector<AxisInfo>& axes);

}  // namespace ncservo::report
