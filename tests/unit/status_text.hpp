// Test helper: a Status as the optional error text that table rows compare against.
#pragma once

#include <optional>
#include <string>

#include "ncservo/error.hpp"

namespace ncservo::test {

inline std::optional<std::string> errorOf(const Status& status) {
  if (status) return std::nullopt;
  return status.error().text();
}

}  // namespace ncservo::test
