// The HTML report's finding timelines (report_charts.hpp): each window draws the rows its rule
// declares it reads, a few frames either side of the finding, with the timeout's window; the caps
// per rule and axis hold.
#include "ncservo/report/report_charts.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "row_name.hpp"
#include "timeline_run.hpp"

namespace ncservo::report {
namespace {

using test::kMs;

using test::record;
using test::Recorded;

struct TimelineRow {
  const char* name;
  test::Script script;
  const char* rule;
  std::vector<std::pair<const char*, std::vector<std::pair<std::int64_t, std::uint64_t>>>> traces;
  std::int64_t start_ns, end_ns;
  std::optional<std::int64_t> since_ns;
  std::optional<std::pair<std::int64_t, std::int64_t>> allowed_ns;
};

class FindingTimelineRows : public ::testing::TestWithParam<TimelineRow> {};

TEST_P(FindingTimelineRows, DrawTheRulesReadsAroundTheFinding) {
  const TimelineRow& row = GetParam();
  const Recorded r = record(row.script);
  // The first timeline of the row's rule.
  const RuleDef& rule = **findRule(row.rule);
  auto of_rule = [&](const FindingTimeline& t) { return r.findings[t.finding].rule == rule.id; };
  const auto found = std::find_if(r.timelines.drawn.begin(), r.timelines.drawn.end(), of_rule);
  ASSERT_NE(found, r.timelines.drawn.end());
  const FindingTimeline& t = *found;
  // Exactly the rows the rule declares it reads, in field-table order.
  const std::vector<FieldRead> reads = fieldsRead(rule.reads);
  ASSERT_EQ(t.traces.size(), reads.size());
  ASSERT_EQ(t.traces.size(), row.traces.size());
  for (std::size_t i = 0; i < t.traces.size(); ++i) {
    EXPECT_EQ(t.traces[i].field, reads[i].field);
    EXPECT_STREQ(t.traces[i].field->filter, row.traces[i].first);
    EXPECT_EQ(t.traces[i].changes, row.traces[i].second) << row.traces[i].first;
  }
  EXPECT_EQ(t.start_ns, row.start_ns);
  EXPECT_EQ(t.end_ns, row.end_ns);
  EXPECT_EQ(t.since_ns, row.since_ns);
  EXPECT_EQ(t.allowed_ns, row.allowed_ns);
  EXPECT_FALSE(t.clipped);
}

// Master and returned copies at one time: 16 frames are 8 cycles.
INSTANTIATE_TEST_SUITE_P(
    Rows, FindingTimelineRows,
    ::testing::Values(
        TimelineRow{
            "illegal_enable_edge",
            test::Script(40).base(test::kScwOff, test::kSswReady).scw(20, 40, test::kScwRunning),
            "SE-001",
            {{"ncservo.scw.se", {{-8 * kMs, 0}, {0, 2}}}},
            -8 * kMs,
            8 * kMs,
            0,
            std::nullopt},
        // ZPulseRequest in cycles 5-9, ZPulseAck from cycle 6 on: the condition begins at
        // cycle 10 and is reported once it outlasts drive_response (20 ms), at cycle 31.
        TimelineRow{
            "zpulse_ack_not_cleared",
            test::Script(60)
                .scw(5, 10, test::kScwRunning | test::kZRequest)
                .ssw(6, 60, test::kSswRunning | test::kZAck),
            "ZP-001",
            {{"ncservo.scw.zpulse_request", {{-29 * kMs, 0}, {-26 * kMs, 1}, {-21 * kMs, 0}}},
             {"ncservo.ssw.zpulse_ack", {{-29 * kMs, 0}, {-25 * kMs, 1}}}},
            -29 * kMs,
            8 * kMs,
            -21 * kMs,
            std::pair{-21 * kMs, -1 * kMs}}),
    test::rowName<TimelineRow>);

TEST(FindingTimelineCaps, FirstFindingsOfEachRuleAndAxisAreDrawnTheRestCounted) {
  // SE-001 on every enable: off and on again every 10 cycles.
  test::Script script(200);
  script.base(test::kScwOff, test::kSswReady);
  for (std::int64_t k = 5; k < 200; k += 10) script.scw(k, k + 5, test::kScwRunning);
  const Recorded r = record(script);
  std::size_t se001 = 0;
  for (const Finding& f : r.findings) se001 += f.rule == RuleId::Se001 ? 1 : 0;
  ASSERT_GT(se001, TimelineRecorder::kPerRuleAndAxis);
  std::size_t drawn = 0;
  for (const FindingTimeline& t : r.timelines.drawn) {
    drawn += r.findings[t.finding].rule == RuleId::Se001 ? 1 : 0;
  }
  EXPECT_EQ(drawn, TimelineRecorder::kPerRuleAndAxis);
  EXPECT_GE(r.timelines.omitted, se001 - drawn);
}

}  // namespace
}  // namespace ncservo::report
