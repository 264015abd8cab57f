// The running cycle-time statistics the rules' "nominal cycle" comes from (interval_stats.hpp,
// docs/timing.md#rule-time): the lower median after every interval, quantiles and the maximum for
// the report, in bounded memory.
#include "ncservo/model/interval_stats.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <queue>
#include <random>
#include <vector>

#include "row_name.hpp"

namespace ncservo {
namespace {

constexpr std::int64_t kUs = 1'000;

// The lower median of everything added so far, kept by two heaps.
class BruteMedian {
 public:
  void add(std::int64_t v) {
    if (low_.empty() || v <= low_.top()) {
      low_.push(v);
    } else {
      high_.push(v);
    }
    if (low_.size() > high_.size() + 1) {
      high_.push(low_.top());
      low_.pop();
    } else if (high_.size() > low_.size()) {
      low_.push(high_.top());
      high_.pop();
    }
  }
  std::int64_t median() const { return low_.top(); }

 private:
  std::priority_queue<std::int64_t> low_;
  std::priority_queue<std::int64_t, std::vector<std::int64_t>, std::greater<>> high_;
};

std::int64_t quantileOf(const std::vector<std::int64_t>& sorted, double q) {
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::max<std::size_t>(rank, 1) - 1];
}

TEST(IntervalStats, EmptyHasNothing) {
  const IntervalStats stats;
  EXPECT_EQ(stats.count(), 0u);
  EXPECT_FALSE(stats.medianNs().has_value());
  EXPECT_FALSE(stats.quantileNs(0.99).has_value());
  EXPECT_FALSE(stats.maxNs().has_value());
  EXPECT_EQ(stats.resolutionNs(), 1'000);
}

// A 1 ms cycle with jitter and some outliers, at 1 µs-rounded values: the running median after
// every interval is exactly the brute-force lower median; p99 and max too.
TEST(IntervalStats, RunningMedianP99AndMaxMatchASortedVector) {
  std::mt19937_64 random(20240611);
  std::uniform_int_distribution<std::int64_t> jitter(-150, 150);
  std::uniform_int_distribution<std::int64_t> outlier(2'000, 12'000);
  std::uniform_int_distribution<int> percent(0, 99);
  IntervalStats stats;
  std::vector<std::int64_t> sorted;
  for (int i = 0; i < 4000; ++i) {
    const std::int64_t us = percent(random) < 3 ? outlier(random) : 1'000 + jitter(random);
    const std::int64_t ns = us * kUs;
    stats.add(ns);
    sorted.insert(std::upper_bound(sorted.begin(), sorted.end(), ns), ns);
    ASSERT_EQ(stats.count(), sorted.size());
    ASSERT_EQ(stats.medianNs(), sorted[(sorted.size() - 1) / 2]) << "after " << sorted.size();
    if (i % 97 == 0 || i == 3999) {
      ASSERT_EQ(stats.quantileNs(0.99), quantileOf(sorted, 0.99)) << "after " << sorted.size();
      ASSERT_EQ(stats.quantileNs(0.5), quantileOf(sorted, 0.5));
      ASSERT_EQ(stats.quantileNs(1.0), sorted.back());
      ASSERT_EQ(stats.quantileNs(0.0), sorted.front());
      ASSERT_EQ(stats.maxNs(), sorted.back());
    }
  }
  EXPECT_EQ(stats.resolutionNs(), 1'000) << "few distinct values: no coarsening";
}

TEST(IntervalStats, ValuesRoundToTheNearestMicrosecondMaxStaysExact) {
  struct Row {
    std::int64_t ns;
    std::int64_t bucket_ns;
  };
  const Row rows[] = {
      {1'000'499, 1'000'000}, {1'000'500, 1'001'000}, {999'501, 1'000'000}, {0, 0}, {-5'000, 0},
  };
  for (const Row& row : rows) {
    SCOPED_TRACE(row.ns);
    IntervalStats stats;
    stats.add(row.ns);
    EXPECT_EQ(stats.medianNs(), row.bucket_ns);
    EXPECT_EQ(stats.maxNs(), row.ns);
  }
}

// More distinct values than kMaxBuckets: the resolution halves (several times here), and the
// running median stays within one resolution step of the exact one.
TEST(IntervalStats, CoarseningKeepsTheMedianWithinTheResolution) {
  std::mt19937_64 random(7);
  std::uniform_int_distribution<std::int64_t> us(1, 200'000);
  IntervalStats stats;
  BruteMedian brute;
  std::vector<std::int64_t> all;
  std::int64_t max = 0;
  for (std::size_t i = 0; i < 60'000; ++i) {
    const std::int64_t ns = us(random) * kUs;
    stats.add(ns);
    brute.add(ns);
    all.push_back(ns);
    max = std::max(max, ns);
    const std::int64_t error = *stats.medianNs() - brute.median();
    ASSERT_LE(std::abs(error), stats.resolutionNs())
        << "after " << i + 1 << " at resolution " << stats.resolutionNs();
  }
  EXPECT_GE(stats.resolutionNs(), 8'000) << "far more distinct values than buckets";
  EXPECT_EQ(stats.maxNs(), max);
  std::sort(all.begin(), all.end());
  EXPECT_LE(std::abs(*stats.quantileNs(0.99) - quantileOf(all, 0.99)), stats.resolutionNs());
}

TEST(IntervalStats, CoarseningAtTheBucketLimit) {
  IntervalStats stats;
  for (std::size_t i = 1; i <= IntervalStats::kMaxBuckets; ++i) {
    stats.add(static_cast<std::int64_t>(i) * kUs);
  }
  EXPECT_EQ(stats.resolutionNs(), 1'000) << "exactly kMaxBuckets distinct values fit";
  EXPECT_EQ(stats.medianNs(), static_cast<std::int64_t>(IntervalStats::kMaxBuckets / 2) * kUs);
  stats.add(static_cast<std::int64_t>(IntervalStats::kMaxBuckets + 1) * kUs);
  EXPECT_EQ(stats.resolutionNs(), 2'000) << "one more halves the resolution";
  const std::int64_t exact = static_cast<std::int64_t>(IntervalStats::kMaxBuckets / 2 + 1) * kUs;
  EXPECT_LE(std::abs(*stats.medianNs() - exact), stats.resolutionNs());
}

// Known inputs, at whole microseconds: the lower median, quantiles by rank ceil(q * n), the
// maximum.
struct KnownCase {
  const char* name;
  std::vector<std::int64_t> us;  // intervals, in the order added
  std::int64_t median_us, min_us, p50_us, p99_us, max_us;
};
const KnownCase kKnownCases[] = {
    {"one interval", {1000}, 1000, 1000, 1000, 1000, 1000},
    {"two: the lower of the middle two", {2000, 1000}, 1000, 1000, 1000, 2000, 2000},
    {"three, out of order", {3000, 1000, 2000}, 2000, 1000, 2000, 3000, 3000},
    {"four", {1000, 2000, 3000, 4000}, 2000, 1000, 2000, 4000, 4000},
    {"repeated values", {1000, 1000, 1000, 5000}, 1000, 1000, 1000, 5000, 5000},
    {"one outlier among a hundred",
     [] {
       std::vector<std::int64_t> v(99, 1000);
       v.push_back(9000);
       return v;
     }(),
     1000, 1000, 1000, 1000, 9000},
    {"1 to 100 ms",
     [] {
       std::vector<std::int64_t> v;
       for (std::int64_t ms = 1; ms <= 100; ++ms) v.push_back(ms * 1000);
       return v;
     }(),
     50'000, 1000, 50'000, 99'000, 100'000},
};

class IntervalStatsKnown : public ::testing::TestWithParam<KnownCase> {};

TEST_P(IntervalStatsKnown, MedianQuantilesAndMax) {
  const KnownCase& c = GetParam();
  IntervalStats stats;
  for (std::int64_t us : c.us) stats.add(us * kUs);
  EXPECT_EQ(stats.count(), c.us.size());
  EXPECT_EQ(stats.medianNs(), c.median_us * kUs);
  EXPECT_EQ(stats.quantileNs(0.0), c.min_us * kUs);
  EXPECT_EQ(stats.quantileNs(0.5), c.p50_us * kUs);
  EXPECT_EQ(stats.quantileNs(0.99), c.p99_us * kUs);
  EXPECT_EQ(stats.quantileNs(1.0), c.max_us * kUs);
  EXPECT_EQ(stats.maxNs(), c.max_us * kUs);
  EXPECT_EQ(stats.quantileNs(-1.0), stats.quantileNs(0.0)) << "q is clamped to [0, 1]";
  EXPECT_EQ(stats.quantileNs(2.0), stats.quantileNs(1.0)) << "q is clamped to [0, 1]";
}

INSTANTIATE_TEST_SUITE_P(Cases, IntervalStatsKnown, ::testing::ValuesIn(kKnownCases),
                         test::rowName<KnownCase>);

struct MergeCase {
  const char* name;
  std::vector<std::int64_t> first, second;
};

// Merging a segment's intervals into the capture's gives what adding them all to one would.
TEST(IntervalStats, MergeEqualsAddingEverything) {
  std::vector<std::int64_t> many;
  for (std::int64_t i = 0; i < 40000; ++i) many.push_back(1000 * (i % 20000) + 7);
  const MergeCase cases[] = {
      {"both empty", {}, {}},
      {"into empty", {}, {1000, 2000, 3000}},
      {"from empty", {1000, 2000}, {}},
      {"two segments", {1000, 1000, 1001, 999}, {250, 251, 249, 5000}},
      {"a coarsened one into a fine one", {1000, 2000}, many},
      {"a fine one into a coarsened one", many, {1000, 2000}},
  };
  for (const MergeCase& c : cases) {
    SCOPED_TRACE(c.name);
    IntervalStats all, first, second;
    for (std::int64_t v : c.first) {
      all.add(v);
      first.add(v);
    }
    for (std::int64_t v : c.second) {
      all.add(v);
      second.add(v);
    }
    first.merge(second);
    const IntervalStats copy(first);
    for (const IntervalStats* merged : {static_cast<const IntervalStats*>(&first), &copy}) {
      EXPECT_EQ(merged->count(), all.count());
      EXPECT_EQ(merged->resolutionNs(), all.resolutionNs());
      EXPECT_EQ(merged->medianNs(), all.medianNs());
      EXPECT_EQ(merged->quantileNs(0.99), all.quantileNs(0.99));
      EXPECT_EQ(merged->maxNs(), all.maxNs());
    }
    second.clear();
    EXPECT_EQ(second.count(), 0u);
    EXPECT_FALSE(second.medianNs().has_value());
  }
}

}  // namespace
}  // namespace ncservo
