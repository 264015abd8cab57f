// `ncservo merge` (report_merge.hpp, docs/field.md#a-fleets-recordings): series merged exactly
// (count, extremes, mean, population standard deviation), histograms laid on one axis by their
// zero and left out when the bins do not line up, counts a report lacks, errors that name the file.
#include "ncservo/report/report_merge.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace ncservo::report {
namespace {

// A report of one capture whose cycle series has the given numbers and one bin.
std::string report(const char* verdict, double mean, double stddev, std::uint64_t count,
                   double zero, double from, double to, const char* extra = "") {
  return "{\"captures\": [{\"path\": \"x.pcap\", \"verdict\": \"" + std::string(verdict) +
         "\", \"frames\": 10, \"cycles\": 5, \"findings\": [{\"rule\": \"SE-001\", \"severity\": "
         "\"error\"}], \"incidents\": [{\"kind\": \"drive-fault\", \"cause\": {\"id\": "
         "\"encoder\"}}], \"timing\": {" +
         extra + "\"cycle_us\": {\"count\": " + std::to_string(count) +
         ", \"min\": " + std::to_string(mean - 1) + ", \"max\": " + std::to_string(mean + 1) +
         ", \"median\": " + std::to_string(zero) + ", \"mean\": " + std::to_string(mean) +
         ", \"stddev\": " + std::to_string(stddev) +
         ", \"histogram\": [{\"from_us\": " + std::to_string(from) +
         ", \"to_us\": " + std::to_string(to) + ", \"count\": " + std::to_string(count) +
         "}], \"histogram_zero\": " + std::to_string(zero) +
         ", \"under\": 0, \"over\": 0}, \"latency_us\": null}}]}";
}

TEST(ReportMerge, SeriesExactAndBinsOnOneAxis) {
  MergedReport m;
  const char* counts = "\"lost_cycles\": 2, \"wkc_errors\": 1, ";
  ASSERT_TRUE(mergeReportText(report("fail", 1000, 3, 100, 1000, 0, 1, counts), "a.json", m));
  // Its zero 1 µs higher, its bin [-1, 0): the same absolute bin [1000, 1001).
  ASSERT_TRUE(mergeReportText(report("pass", 1002, 4, 300, 1001, -1, 0, counts), "b.json", m));
  EXPECT_EQ(m.captures, 2u);
  EXPECT_EQ(m.verdicts.at("fail"), 1u);
  EXPECT_EQ(m.verdicts.at("pass"), 1u);
  EXPECT_EQ(m.frames, 20u);
  EXPECT_EQ(m.lost_cycles, 4u);
  EXPECT_EQ(m.wkc_errors, 2u);
  EXPECT_EQ(m.findings_by_rule.at("SE-001"), 2u);
  EXPECT_EQ(m.incidents_by_cause.at("encoder"), 2u);
  ASSERT_TRUE(m.cycle);
  EXPECT_EQ(m.cycle->count, 400u);
  EXPECT_DOUBLE_EQ(m.cycle->min, 999);
  EXPECT_DOUBLE_EQ(m.cycle->max, 1003);
  // Mean (100 × 1000 + 300 × 1002) / 400 = 1001.5; variance from the parts, written out:
  // (100 × (9 + 1000²) + 300 × (16 + 1002²)) / 400 − 1001.5² = 14.25 + 0.75 = 15.
  EXPECT_DOUBLE_EQ(m.cycle->mean(), 1001.5);
  EXPECT_NEAR(m.cycle->stddev(), std::sqrt(15.0), 1e-6);
  ASSERT_EQ(m.cycle->bins.size(), 1u);
  EXPECT_EQ(m.cycle->bins.begin()->first, 1'000'000);
  EXPECT_EQ(m.cycle->bins.begin()->second,
            std::make_pair(std::int64_t{1'001'000}, std::uint64_t{400}));
  const auto p99 = m.cycle->quantileBin(0.99);
  ASSERT_TRUE(p99);
  EXPECT_EQ(*p99, std::make_pair(1000.0, 1001.0));
}

TEST(ReportMerge, BinsThatDoNotLineUpAreLeftOut) {
  MergedReport m;
  ASSERT_TRUE(mergeReportText(report("pass", 1000, 0, 10, 1000, 0, 1), "a.json", m));
  // A zero half a bin away: [1000.5, 1001.5) overlaps [1000, 1001).
  ASSERT_TRUE(mergeReportText(report("pass", 1000, 0, 10, 1000.5, 0, 1), "b.json", m));
  ASSERT_TRUE(m.cycle);
  EXPECT_EQ(m.cycle->count, 20u);
  EXPECT_EQ(m.cycle->not_aligned, "b.json: x.pcap");
  EXPECT_FALSE(m.cycle->quantileBin(0.5));
  EXPECT_NE(mergedJson(m).find("\"histogram\": null"), std::string::npos);
}

TEST(ReportMerge, CountsAReportLacksAreNone) {
  MergedReport m;
  ASSERT_TRUE(mergeReportText(report("pass", 1000, 0, 1, 1000, 0, 1, "\"lost_cycles\": 1, "),
                              "new.json", m));
  ASSERT_TRUE(mergeReportText(report("pass", 1000, 0, 1, 1000, 0, 1), "old.json", m));
  EXPECT_FALSE(m.lost_cycles);
  EXPECT_NE(mergedJson(m).find("\"lost_cycles\": null"), std::string::npos);
}

TEST(ReportMerge, ErrorsNameTheFileAndChangeNothing) {
  MergedReport m;
  ASSERT_TRUE(mergeReportText(report("pass", 1000, 0, 1, 1000, 0, 1), "a.json", m));
  const auto not_json = mergeReportText("pcap bytes", "capture.pcap", m);
  ASSERT_FALSE(not_json);
  EXPECT_EQ(not_json.error().text().rfind("capture.pcap: not JSON (", 0), 0u);
  const auto other = mergeReportText("{\"runs\": []}", "sarif.json", m);
  ASSERT_FALSE(other);
  EXPECT_EQ(
      other.error().text(),
      "sarif.json: not a JSON report of ncservo validate (--format json): no 'captures' list");
  const auto broken = mergeReportText("{\"captures\": [{\"path\": \"y\"}]}", "b.json", m);
  ASSERT_FALSE(broken);
  EXPECT_EQ(broken.error().path, "b.json");
  EXPECT_EQ(m.captures, 1u);
  EXPECT_EQ(m.reports, std::vector<std::string>{"a.json"});
}

}  // namespace
}  // namespace ncservo::report
