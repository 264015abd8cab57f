#include "ncservo/report/axis_selection.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace ncservo::report {

namespace {
bool names(const std::string& entry, const AxisInfo& axis) {
  return entry == axis.name || entry == std::to_string(axis.index);
}
}  // namespace

bool axisSelected(const std::vector<std::string>& wanted, const AxisInfo& axis) {
  return wanted.empty() ||
         std::any_of(wanted.begin(), wanted.end(), [&](const auto& e) { return names(e, axis); });
}

Status checkAxisSelection(const std::vector<std::string>& wanted,
                          const std::vector<AxisInfo>& axes) {
  std::string unknown;
  for (const std::string& entry : wanted) {
    const bool found =
        std::any_of(axes.begin(), axes.end(), [&](const AxisInfo& a) { return names(entry, a); });
    if (!found) unknown += fmt::format("{}{}", unknown.empty() ? "" : ", ", entry);
  }
  if (unknown.empty()) return {};
  std::string known;
  for (const AxisInfo& axis : axes) {
    known += fmt::format("{}{} ({})", known.empty() ? "" : ", ", axis.index, axis.name);
  }
  return fail(fmt::format("--axis {}: no such axis; the axes are {}", unknown,
                          known.empty() ? "none" : known));
}

}  // namespace ncservo::report
