// Test helper: a Status as the optional error text that table rows compare against.
#pragma once

#include <optional>
#include <string>

#include "ncservo/base/error.hpp"

namespace ncservo::test {

inline std::optional<std::string> errorOf(const Status& status) {
  if (status) return std::nullopt;
  return status.error().text();
}

// "" for success, else the error's text: for rows that expect a message or none.
inline std::string statusText(const Status& status) {
  return status ? std::string() : status.error().text();
}

}  // namespace ncservo::test
