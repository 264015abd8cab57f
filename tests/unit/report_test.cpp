// The pure parts of `validate`'s reports (report.hpp): absolute times in ISO 8601, the capture's
// timestamp precision from its header, findings counted by rule and axis, the rules' anchors.
#include "ncservo/report/report.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "row_name.hpp"

namespace ncservo::report {
namespace {

struct IsoRow {
  const char* name;
  std::int64_t time_ns;
  int digits;
  const char* expected;
};

class IsoUtc : public ::testing::TestWithParam<IsoRow> {};

TEST_P(IsoUtc, FormatsInUtcWithTheCapturesDigits) {
  const IsoRow& row = GetParam();
  EXPECT_EQ(isoUtc(row.time_ns, row.digits), row.expected);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, IsoUtc,
    ::testing::Values(
        IsoRow{"epoch_micro", 0, 6, "1970-01-01T00:00:00.000000Z"},
        IsoRow{"micro_truncates", 1714564800123456789, 6, "2024-05-01T12:00:00.123456Z"},
        IsoRow{"nano", 1714564800123456789, 9, "2024-05-01T12:00:00.123456789Z"},
        IsoRow{"whole_seconds", 1714564800999999999, 0, "2024-05-01T12:00:00Z"},
        IsoRow{"millis", 1714564800007000000, 3, "2024-05-01T12:00:00.007Z"},
        IsoRow{"leap_day", 951782400000000000, 6, "2000-02-29T00:00:00.000000Z"},
        IsoRow{"end_of_pcap_range", 4294967295000000000, 6, "2106-02-07T06:28:15.000000Z"},
        IsoRow{"digits_clamped", 1500000000, 12, "1970-01-01T00:00:01.500000000Z"},
        IsoRow{"negative_digits_clamped", 1500000000, -3, "1970-01-01T00:00:01Z"},
        IsoRow{"before_the_epoch", -1, 6, "1969-12-31T23:59:59.999999Z"},
        IsoRow{"one_digit", 1714564800987654321, 1, "2024-05-01T12:00:00.9Z"},
        IsoRow{"next_second", 1714564801000000001, 9, "2024-05-01T12:00:01.000000001Z"}),
    test::rowName<IsoRow>);

// writeSeconds against fmt's "{:.6f}" of ns / 1e9, which the text report wrote before: the same
// digits, halfway cases (ns ending in 500), the limit of exact doubles and negative times included.
// isoUtc keeps the calendar text of the last second it was asked for: times in one second, then
// in another, then in the first again, each as if asked alone.
TEST(IsoUtcSequence, KeepsNoTextOfAnotherSecond) {
  const std::vector<std::pair<std::int64_t, const char*>> asked{
      {1714564800000000000, "2024-05-01T12:00:00.000000Z"},
      {1714564800999999999, "2024-05-01T12:00:00.999999Z"},
      {1714564801000000000, "2024-05-01T12:00:01.000000Z"},
      {-1000000000, "1969-12-31T23:59:59.000000Z"},
      {1714564800000000001, "2024-05-01T12:00:00.000000Z"},
      {951782400000000000, "2000-02-29T00:00:00.000000Z"},
  };
  for (const auto& [time_ns, expected] : asked) EXPECT_EQ(isoUtc(time_ns, 6), expected) << time_ns;
}

struct SecondsRow {
  const char* name;
  std::int64_t first_ns;
  std::int64_t count;  // consecutive values from first_ns
  std::int64_t step;
};

class WriteSeconds : public ::testing::TestWithParam<SecondsRow> {};

TEST_P(WriteSeconds, WritesTheDigitsOfFixedSixDecimals) {
  const SecondsRow& row = GetParam();
  for (std::int64_t k = 0; k < row.count; ++k) {
    const std::int64_t ns = row.first_ns + k * row.step;
    char text[kSecondsTextSize];
    const std::string written(text, writeSeconds(ns, text));
    ASSERT_EQ(written, fmt::format("{:.6f}", static_cast<double>(ns) / 1e9)) << "ns = " << ns;
  }
}

constexpr std::int64_t kTwoTo53 = std::int64_t{1} << 53;

INSTANTIATE_TEST_SUITE_P(
    Rows, WriteSeconds,
    ::testing::Values(
        SecondsRow{"zero_to_3000", 0, 3001, 1}, SecondsRow{"halfway_small", 500, 2000, 1000},
        SecondsRow{"around_one_second", 999998000, 4001, 1},
        SecondsRow{"hour_halfway", 3600000000500, 1000, 1000},
        SecondsRow{"day_steps", 86399999999000, 2001, 1},
        SecondsRow{"year_halfway", 31536000000000500, 1000, 1000},
        SecondsRow{"below_exact_limit", kTwoTo53 - 2000, 2000, 1},
        SecondsRow{"exact_limit_and_above", kTwoTo53, 2000, 1},
        SecondsRow{"negative", -3000, 3000, 1}, SecondsRow{"spread", 1, 100000, 90071992547},
        SecondsRow{"int64_max", INT64_MAX, 1, 0}, SecondsRow{"int64_min", INT64_MIN, 1, 0}),
    test::rowName<SecondsRow>);

struct DigitsRow {
  const char* name;
  std::vector<std::uint8_t> head;
  int expected;
};

// A pcapng section header (28 bytes, little-endian) and an interface block with these options.
std::vector<std::uint8_t> pcapng(std::vector<std::uint8_t> options, bool big_endian = false) {
  auto put32 = [&](std::vector<std::uint8_t>& out, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) {
      const int shift = big_endian ? 24 - 8 * i : 8 * i;
      out.push_back(static_cast<std::uint8_t>(v >> shift));
    }
  };
  std::vector<std::uint8_t> out;
  put32(out, 0x0A0D0D0A);
  put32(out, 28);
  put32(out, 0x1A2B3C4D);
  for (int i = 0; i < 12; ++i) out.push_back(i < 4 ? (big_endian ? i == 1 : i == 0) : 0xFF);
  put32(out, 28);
  const std::uint32_t length = 20 + static_cast<std::uint32_t>(options.size());
  put32(out, 1);
  put32(out, length);
  put32(out, 1);       // link type, reserved
  put32(out, 0xFFFF);  // snap length
  out.insert(out.end(), options.begin(), options.end());
  put32(out, length);
  return out;
}

class TimestampDigits : public ::testing::TestWithParam<DigitsRow> {};

TEST_P(TimestampDigits, ReadsThePrecisionFromTheHeader) {
  const DigitsRow& row = GetParam();
  EXPECT_EQ(timestampDigits(row.head.data(), row.head.size()), row.expected);
}

// Options: code 2 (if_name, 3 bytes padded to 4) first, then if_tsresol (code 9), then the end.
INSTANTIATE_TEST_SUITE_P(
    Rows, TimestampDigits,
    ::testing::Values(
        DigitsRow{"pcap_micro_le", {0xD4, 0xC3, 0xB2, 0xA1, 2, 0, 4, 0, 0, 0, 0, 0}, 6},
        DigitsRow{"pcap_micro_be", {0xA1, 0xB2, 0xC3, 0xD4, 0, 2, 0, 4, 0, 0, 0, 0}, 6},
        DigitsRow{"pcap_nano_le", {0x4D, 0x3C, 0xB2, 0xA1, 2, 0, 4, 0, 0, 0, 0, 0}, 9},
        DigitsRow{"pcap_nano_be", {0xA1, 0xB2, 0x3C, 0x4D, 0, 2, 0, 4, 0, 0, 0, 0}, 9},
        DigitsRow{"pcapng_default_micro", pcapng({0, 0, 0, 0}), 6},
        DigitsRow{"pcapng_nano", pcapng({9, 0, 1, 0, 9, 0, 0, 0, 0, 0, 0, 0}), 9},
        DigitsRow{"pcapng_after_name",
                  pcapng({2, 0, 3, 0, 'e', 't', 'h', 0, 9, 0, 1, 0, 3, 0, 0, 0, 0, 0, 0, 0}), 3},
        DigitsRow{"pcapng_power_of_two", pcapng({9, 0, 1, 0, 0x80 | 20, 0, 0, 0, 0, 0, 0, 0}), 7},
        DigitsRow{"pcapng_big_endian", pcapng({0, 9, 0, 1, 9, 0, 0, 0, 0, 0, 0, 0}, true), 9},
        DigitsRow{"too_short", {0xD4, 0xC3}, 6},
        DigitsRow{
            "not_a_capture", {'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd', '!'}, 6}),
    test::rowName<DigitsRow>);

Finding finding(RuleId rule, std::optional<std::uint16_t> axis, std::uint64_t frame,
                Severity severity = Severity::Warning) {
  return {rule, severity, axis, {frame, 0}, {frame, 0}, "at " + std::to_string(frame)};
}

TEST(FindingGroups, OneGroupPerRuleAndAxisInTheOrderOfTheFirstFinding) {
  CaptureReport report;
  const std::vector<Finding> findings = {
      finding(RuleId::Com004, std::nullopt, 10), finding(RuleId::Se001, 0, 12, Severity::Error),
      finding(RuleId::Com004, std::nullopt, 20), finding(RuleId::Se001, 1, 30, Severity::Error),
      finding(RuleId::Com004, std::nullopt, 40)};
  for (const Finding& f : findings) report.tally(f);
  ASSERT_EQ(report.groups.size(), 3u);
  const FindingGroup& bus = report.groups[0];
  EXPECT_EQ(bus.rule, RuleId::Com004);
  EXPECT_FALSE(bus.axis.has_value());
  EXPECT_EQ(bus.count, 3u);
  EXPECT_EQ(bus.first.frame, 10u);
  EXPECT_EQ(bus.last.frame, 40u);
  EXPECT_EQ(bus.first_message, "at 10");
  EXPECT_EQ(report.groups[1].axis, std::optional<std::uint16_t>(0));
  EXPECT_EQ(report.groups[2].axis, std::optional<std::uint16_t>(1));
  EXPECT_EQ(report.groups[2].count, 1u);
  EXPECT_EQ(report.count(Severity::Warning), 3u);
  EXPECT_EQ(report.count(Severity::Error), 2u);
}

TEST(RuleAnchors, AreTheLowerCaseIdsAndUniqueAndHelpUrisPointIntoTheRuleReference) {
  std::vector<std::string> anchors;
  for (const RuleDef& rule : kRules) {
    const std::string anchor = ruleAnchor(rule);
    EXPECT_EQ(anchor.size(), std::string(rule.code).size());
    EXPECT_NE(ruleHelpUri(rule).find("/docs/rules.md#" + anchor), std::string::npos);
    EXPECT_EQ(ruleHelpUri(rule).rfind("https://", 0), 0u);
    anchors.push_back(anchor);
  }
  EXPECT_EQ(ruleAnchor(ruleDef(RuleId::Se001)), "se-001");
  std::sort(anchors.begin(), anchors.end());
  EXPECT_EQ(std::unique(anchors.begin(), anchors.end()), anchors.end());
}

}  // namespace
}  // namespace ncservo::report
