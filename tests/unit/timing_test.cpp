// The timing statistics (timing.hpp, docs/timing.md) against a sorted exact computation: moments,
// nearest-rank quantiles, the deviation histogram and the worst lists; beyond kExactSamples the
// quantiles stay within half a histogram bin. The validator's per-frame timing gives what the
// statistics took from each frame.
#include "ncservo/model/timing.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "ncservo/model/timing_text.hpp"
#include "row_name.hpp"
#include "validator_driver.hpp"

namespace ncservo {
namespace {

constexpr std::int64_t kUs = 1'000;

std::int64_t quantileOf(const std::vector<std::int64_t>& sorted, double q) {
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::max<std::size_t>(rank, 1) - 1];
}

struct SeriesRow {
  std::string name;
  std::size_t count;
  std::int64_t nominal_ns;
  std::int64_t jitter_ns;  // uniform ±
  int outlier_percent;     // samples far out (late cycles)
  std::uint64_t seed;
};

class TimingSeriesExact : public ::testing::TestWithParam<SeriesRow> {};

TEST_P(TimingSeriesExact, MatchesASortedComputation) {
  const SeriesRow& row = GetParam();
  std::mt19937_64 random(row.seed);
  std::uniform_int_distribution<std::int64_t> jitter(-row.jitter_ns, row.jitter_ns);
  std::uniform_int_distribution<int> percent(0, 99);
  std::uniform_int_distribution<std::int64_t> outlier(2 * row.nominal_ns, 9 * row.nominal_ns);
  TimingSeries series;
  std::vector<std::int64_t> all;
  for (std::size_t i = 0; i < row.count; ++i) {
    const std::int64_t ns =
        percent(random) < row.outlier_percent ? outlier(random) : row.nominal_ns + jitter(random);
    series.add(ns);
    all.push_back(ns);
  }
  const std::optional<SeriesSummary> s = series.summary();
  ASSERT_TRUE(s);
  std::sort(all.begin(), all.end());
  EXPECT_TRUE(s->exact);
  EXPECT_EQ(s->count, all.size());
  EXPECT_EQ(s->min_ns, all.front());
  EXPECT_EQ(s->max_ns, all.back());
  EXPECT_EQ(s->median_ns, quantileOf(all, 0.5));
  EXPECT_EQ(s->p1_ns, quantileOf(all, 0.01));
  EXPECT_EQ(s->p99_ns, quantileOf(all, 0.99));
  EXPECT_EQ(s->p999_ns, quantileOf(all, 0.999));
  EXPECT_EQ(s->reference_ns, s->median_ns);
  const double mean =
      static_cast<double>(std::accumulate(all.begin(), all.end(), std::int64_t{0})) /
      static_cast<double>(all.size());
  double squares = 0;
  for (std::int64_t v : all)
    squares += (static_cast<double>(v) - mean) * (static_cast<double>(v) - mean);
  EXPECT_NEAR(s->mean_ns, mean, 1e-6 * std::abs(mean) + 1e-9);
  EXPECT_NEAR(s->stddev_ns, std::sqrt(squares / static_cast<double>(all.size())),
              1e-6 * s->stddev_ns + 1e-6);
  // Every sample in exactly one bin (or under/over), each bin holding what lies in it.
  std::uint64_t binned = s->under + s->over;
  for (const HistogramBin& bin : s->histogram) {
    const auto in =
        static_cast<std::uint64_t>(std::count_if(all.begin(), all.end(), [&](std::int64_t v) {
          return v - s->median_ns >= bin.from_ns && v - s->median_ns < bin.to_ns;
        }));
    EXPECT_EQ(bin.count, in) << "bin " << bin.from_ns << ".." << bin.to_ns;
    binned += bin.count;
  }
  EXPECT_EQ(binned, all.size());
  EXPECT_EQ(s->over,
            static_cast<std::uint64_t>(std::count_if(all.begin(), all.end(), [&](std::int64_t v) {
              return v - s->median_ns >= 5'000 * kUs;
            })));
}

INSTANTIATE_TEST_SUITE_P(
    Rows, TimingSeriesExact,
    ::testing::Values(SeriesRow{"one sample", 1, 1'000 * kUs, 0, 0, 1},
                      SeriesRow{"two samples", 2, 1'000 * kUs, 30 * kUs, 0, 2},
                      SeriesRow{"steady 1 ms", 5'000, 1'000 * kUs, 0, 0, 3},
                      SeriesRow{"1 ms, ±20 us, ns timestamps", 20'000, 1'000 * kUs, 20'000, 0, 4},
                      SeriesRow{"250 us, ±3 us", 20'000, 250 * kUs, 3 * kUs, 0, 5},
                      SeriesRow{"1 ms with 2 % late cycles", 20'000, 1'000 * kUs, 40 * kUs, 2, 6},
                      SeriesRow{"10 ms, ±400 us", 9'000, 10'000 * kUs, 400 * kUs, 1, 7},
                      SeriesRow{"exactly the exact limit", TimingSeries::kExactSamples, 1'000 * kUs,
                                15 * kUs, 1, 8}),
    test::rowName<SeriesRow>);

TEST(TimingSeries, EmptyHasNoSummary) {
  EXPECT_FALSE(TimingSeries{}.summary());
}

// Past kExactSamples: quantiles from the histogram, within half a bin of the exact ones; the
// moments, min and max stay exact.
TEST(TimingSeries, BeyondTheExactLimitQuantilesStayWithinHalfABin) {
  std::mt19937_64 random(11);
  std::normal_distribution<double> jitter(0, 8'000);
  TimingSeries series;
  std::vector<std::int64_t> all;
  for (std::size_t i = 0; i < TimingSeries::kExactSamples * 3; ++i) {
    const auto ns = static_cast<std::int64_t>(1'000'000 + std::llround(jitter(random)));
    series.add(ns);
    all.push_back(ns);
  }
  const SeriesSummary s = *series.summary();
  std::sort(all.begin(), all.end());
  EXPECT_FALSE(s.exact);
  EXPECT_EQ(s.min_ns, all.front());
  EXPECT_EQ(s.max_ns, all.back());
  for (const auto& [q, value] : {std::pair{0.5, s.median_ns}, std::pair{0.01, s.p1_ns},
                                 std::pair{0.99, s.p99_ns}, std::pair{0.999, s.p999_ns}}) {
    EXPECT_LE(std::abs(value - quantileOf(all, q)), 500) << "q " << q;
  }
  std::uint64_t binned = s.under + s.over;
  for (const HistogramBin& bin : s.histogram) binned += bin.count;
  EXPECT_EQ(binned, all.size());
}

// A sample more than 2.1 s from the first cannot be kept as an offset: the histogram takes over,
// min and max stay exact.
TEST(TimingSeries, ASampleFarFromTheFirstEndsTheExactQuantiles) {
  TimingSeries series;
  for (int i = 0; i < 10; ++i) series.add(1'000 * kUs);
  series.add(3'000'000 * kUs);
  const SeriesSummary s = *series.summary();
  EXPECT_FALSE(s.exact);
  EXPECT_EQ(s.reference_ns, 1'000 * kUs);
  EXPECT_EQ(s.max_ns, 3'000'000 * kUs);
  EXPECT_EQ(s.median_ns, 1'000 * kUs + kUs / 2);  // the middle of the bin [0, 1 µs)
  EXPECT_EQ(s.over, 1u);
}

TEST(WorstList, KeepsTheTenLargestWorstFirstEarlierFirstOnTies) {
  struct Row {
    std::string name;
    std::vector<std::int64_t> values;  // frame = index + 1
    std::vector<std::uint64_t> frames;
  };
  const Row rows[] = {
      {"fewer than ten", {5, 9, 1}, {2, 1, 3}},
      {"ties keep the earlier", {7, 7, 3, 7}, {1, 2, 4, 3}},
      {"the ten largest",
       {1, 20, 3, 19, 5, 18, 7, 17, 9, 16, 11, 15, 13, 14},
       {2, 4, 6, 8, 10, 12, 14, 13, 11, 9}},
  };
  for (const Row& row : rows) {
    SCOPED_TRACE(row.name);
    WorstList worst;
    for (std::size_t i = 0; i < row.values.size(); ++i) worst.add({i + 1, i, row.values[i]});
    std::vector<std::uint64_t> frames;
    for (const TimedFrames& e : worst.entries()) frames.push_back(e.frame);
    EXPECT_EQ(frames, row.frames);
  }
}

struct FrameTimingRow {
  std::string name;
  test::Script script;
  test::At at;  // the script runs up to this frame
  std::optional<std::int64_t> interval_ns, deviation_ns, latency_ns;
};

TEST(FrameTiming, GivesWhatTheStatisticsTookFromTheFrame) {
  using test::M;
  using test::R;
  const std::int64_t ms = test::kMs;
  const std::int64_t us = test::kUs;
  const FrameTimingRow rows[] = {
      {"the first master copy closes no interval",
       test::Script(1).noReturned(0, 1),
       M(0),
       {},
       {},
       {}},
      {"an interval before the nominal cycle is known",
       test::Script(2).noReturned(1, 2),
       M(1),
       ms,
       {},
       {}},
      {"an interval on the nominal cycle", test::Script(21).noReturned(20, 21), M(20), ms, 0, {}},
      {"a late cycle",
       test::Script(21).noReturned(20, 21).time(M(20), test::kEpochNs + 20 * ms + 50 * us),
       M(20),
       ms + 50 * us,
       50 * us,
       {}},
      {"the short cycle after it",
       test::Script(22).noReturned(21, 22).time(M(20), test::kEpochNs + 20 * ms + 50 * us),
       M(21),
       ms - 50 * us,
       -50 * us,
       {}},
      {"a returned copy's latency", test::Script(6).delay(300 * us), R(5), {}, {}, 300 * us},
      {"a returned copy without its master copy", test::Script(6).noMaster(5, 6), R(5), {}, {}, {}},
  };
  for (const FrameTimingRow& row : rows) {
    SCOPED_TRACE(row.name);
    test::ValidatorDriver driver;
    driver.run(row.script);
    const FrameTiming& timing = driver.validator().frameTiming();
    EXPECT_EQ(timing.frame, driver.frameOf(row.at));
    EXPECT_EQ(driver.frames(), driver.frameOf(row.at));
    EXPECT_EQ(timing.interval_ns, row.interval_ns);
    EXPECT_EQ(timing.deviation_ns, row.deviation_ns);
    EXPECT_EQ(timing.latency_ns, row.latency_ns);
  }
}

// Each count agrees with its noun and verb: "1 returned copy", never "1 returned copies".
TEST(CopiesMissingText, AgreesWithItsCounts) {
  struct Row {
    std::uint64_t master, returned;
    const char* text;
  };
  const Row rows[] = {
      {0, 0, ""},
      {0, 1,
       "0 master copies missing from the capture (their returned copies prove the cycles ran), "
       "1 returned copy never came"},
      {1, 0,
       "1 master copy missing from the capture (its returned copy proves the cycle ran), 0 "
       "returned copies never came"},
      {2, 3,
       "2 master copies missing from the capture (their returned copies prove the cycles ran), "
       "3 returned copies never came"},
  };
  for (const Row& row : rows) {
    EXPECT_EQ(copiesMissingText(row.master, row.returned), row.text)
        << row.master << ", " << row.returned;
  }
}

}  // namespace
}  // namespace ncservo
