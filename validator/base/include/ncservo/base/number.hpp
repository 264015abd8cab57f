// The one number parser of the command line, the simulator's settings and the ENI import: the
// whole text as a number, or an error saying what was expected. Nothing here throws.
#pragma once

#include <fmt/format.h>

#include <charconv>
#include <string_view>
#include <system_error>
#include <type_traits>

#include "ncservo/base/error.hpp"

namespace ncservo {

// The whole of `text` as a T: an integer in `base` (no "0x" prefix: the caller strips its own),
// or for a floating-point T a decimal number ("1.5", "2e-3"). An optional leading '+'; no
// spaces, nothing after the number.
template <class T>
Result<T> parseNumber(std::string_view text, int base = 10) {
  static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>, "a number type");
  constexpr const char* kExpected =
      std::is_floating_point_v<T> ? "expected a number" : "expected a whole number";
  std::string_view digits = text;
  // from_chars takes a '-' but no '+'; a second sign stays an error.
  if (digits.size() > 1 && digits.front() == '+' && digits[1] != '-' && digits[1] != '+') {
    digits.remove_prefix(1);
  }
  T value{};
  const char* end = digits.data() + digits.size();
  std::from_chars_result parsed;
  if constexpr (std::is_floating_point_v<T>) {
    parsed = std::from_chars(digits.data(), end, value);
  } else {
    parsed = std::from_chars(digits.data(), end, value, base);
  }
  if (parsed.ec == std::errc::result_out_of_range) {
    return fail(fmt::format("'{}': out of range", text));
  }
  if (digits.empty() || parsed.ec != std::errc{} || parsed.ptr != end) {
    return fail(fmt::format("'{}': {}", text, kExpected));
  }
  return value;
}

}  // namespace ncservo
