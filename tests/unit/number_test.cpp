// The one number parser (number.hpp): the whole text or an error, never an exception.
#include "ncservo/base/number.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>

namespace ncservo {
namespace {

template <class T>
struct NumberCase {
  const char* text;
  int base;
  std::optional<T> value;  // nullopt: an error
  const char* error;       // its message, when an error
};

const NumberCase<std::int64_t> kIntegerCases[] = {
    {.text = "0", .base = 10, .value = 0, .error = ""},
    {.text = "42", .base = 10, .value = 42, .error = ""},
    {.text = "+42", .base = 10, .value = 42, .error = ""},
    {.text = "-1", .base = 10, .value = -1, .error = ""},
    {.text = "9223372036854775807", .base = 10, .value = INT64_MAX, .error = ""},
    {.text = "1A00", .base = 16, .value = 0x1A00, .error = ""},
    {.text = "ff", .base = 16, .value = 0xFF, .error = ""},
    {.text = "9223372036854775808",
     .base = 10,
     .value = std::nullopt,
     .error = "'9223372036854775808': out of range"},
    {.text = "", .base = 10, .value = std::nullopt, .error = "'': expected a whole number"},
    {.text = "+", .base = 10, .value = std::nullopt, .error = "'+': expected a whole number"},
    {.text = "++1", .base = 10, .value = std::nullopt, .error = "'++1': expected a whole number"},
    {.text = "+-1", .base = 10, .value = std::nullopt, .error = "'+-1': expected a whole number"},
    {.text = "1.5", .base = 10, .value = std::nullopt, .error = "'1.5': expected a whole number"},
    {.text = "12ms", .base = 10, .value = std::nullopt, .error = "'12ms': expected a whole number"},
    {.text = " 1", .base = 10, .value = std::nullopt, .error = "' 1': expected a whole number"},
    {.text = "1 ", .base = 10, .value = std::nullopt, .error = "'1 ': expected a whole number"},
    {.text = "0x10", .base = 16, .value = std::nullopt, .error = "'0x10': expected a whole number"},
    {.text = "abc", .base = 10, .value = std::nullopt, .error = "'abc': expected a whole number"},
};

TEST(Number, Integer) {
  for (const NumberCase<std::int64_t>& c : kIntegerCases) {
    SCOPED_TRACE(c.text);
    const Result<std::int64_t> parsed = parseNumber<std::int64_t>(c.text, c.base);
    ASSERT_EQ(parsed.has_value(), c.value.has_value());
    if (c.value) {
      EXPECT_EQ(*parsed, *c.value);
    } else {
      EXPECT_EQ(parsed.error().message, c.error);
    }
  }
}

const NumberCase<int> kIntCases[] = {
    {.text = "2147483647", .base = 10, .value = 2147483647, .error = ""},
    {.text = "2147483648",
     .base = 10,
     .value = std::nullopt,
     .error = "'2147483648': out of range"},
    {.text = "-3", .base = 10, .value = -3, .error = ""},
};

TEST(Number, IntRange) {
  for (const NumberCase<int>& c : kIntCases) {
    SCOPED_TRACE(c.text);
    const Result<int> parsed = parseNumber<int>(c.text, c.base);
    ASSERT_EQ(parsed.has_value(), c.value.has_value());
    if (c.value) {
      EXPECT_EQ(*parsed, *c.value);
    } else {
      EXPECT_EQ(parsed.error().message, c.error);
    }
  }
}

const NumberCase<double> kDecimalCases[] = {
    {.text = "0", .base = 10, .value = 0.0, .error = ""},
    {.text = "1.5", .base = 10, .value = 1.5, .error = ""},
    {.text = "+1.5", .base = 10, .value = 1.5, .error = ""},
    {.text = "-0.25", .base = 10, .value = -0.25, .error = ""},
    {.text = ".5", .base = 10, .value = 0.5, .error = ""},
    {.text = "2e-3", .base = 10, .value = 0.002, .error = ""},
    {.text = "3", .base = 10, .value = 3.0, .error = ""},
    {.text = "1e400", .base = 10, .value = std::nullopt, .error = "'1e400': out of range"},
    {.text = "", .base = 10, .value = std::nullopt, .error = "'': expected a number"},
    {.text = "1.5s", .base = 10, .value = std::nullopt, .error = "'1.5s': expected a number"},
    {.text = "1,5", .base = 10, .value = std::nullopt, .error = "'1,5': expected a number"},
    {.text = " 1.5", .base = 10, .value = std::nullopt, .error = "' 1.5': expected a number"},
    {.text = "x", .base = 10, .value = std::nullopt, .error = "'x': expected a number"},
};

TEST(Number, Decimal) {
  for (const NumberCase<double>& c : kDecimalCases) {
    SCOPED_TRACE(c.text);
    const Result<double> parsed = parseNumber<double>(c.text);
    ASSERT_EQ(parsed.has_value(), c.value.has_value());
    if (c.value) {
      EXPECT_DOUBLE_EQ(*parsed, *c.value);
    } else {
      EXPECT_EQ(parsed.error().message, c.error);
    }
  }
}

}  // namespace
}  // namespace ncservo
