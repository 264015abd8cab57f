// Capture discontinuities (docs/cli.md, docs/protocol.md §8): where segments start and what they
// span.
#include "ncservo/model/capture_segments.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <vector>

namespace ncservo {
namespace {

constexpr std::int64_t kUs = 1000;
constexpr std::int64_t kMs = 1000 * kUs;
constexpr std::int64_t kPause = 1000 * kMs;  // capture_pause's default

struct JumpCase {
  const char* name;
  std::int64_t latest_ns;
  std::int64_t time_ns;
  std::optional<std::int64_t> cycle_ns;
  Discontinuity expected;
};

TEST(Discontinuity, BackByMoreThanACycleOrForwardByMoreThanThePause) {
  const JumpCase cases[] = {
      {"the next cycle", 10 * kMs, 11 * kMs, kMs, Discontinuity::None},
      {"the same time", 10 * kMs, 10 * kMs, kMs, Discontinuity::None},
      {"a few microseconds back", 10 * kMs, 10 * kMs - 5 * kUs, kMs, Discontinuity::None},
      {"back by exactly a cycle", 10 * kMs, 9 * kMs, kMs, Discontinuity::None},
      {"back by more than a cycle", 10 * kMs, 9 * kMs - 1, kMs, Discontinuity::Back},
      {"back by 300 us with a 250 us cycle", 10 * kMs, 10 * kMs - 300 * kUs, 250 * kUs,
       Discontinuity::Back},
      {"back by 300 us, no cycle known yet: under the floor", 10 * kMs, 10 * kMs - 300 * kUs,
       std::nullopt, Discontinuity::None},
      {"back by the floor, no cycle known yet", 10 * kMs, 10 * kMs - kBackJumpFloorNs, std::nullopt,
       Discontinuity::None},
      {"back by more than the floor, no cycle known yet", 10 * kMs, 10 * kMs - kBackJumpFloorNs - 1,
       std::nullopt, Discontinuity::Back},
      {"back to the start of a recording", 5000 * kMs, 0, kMs, Discontinuity::Back},
      {"forward by the pause exactly", 0, kPause, kMs, Discontinuity::None},
      {"forward by more than the pause", 0, kPause + 1, kMs, Discontinuity::Forward},
      {"an hour's pause", 3 * kMs, 3600'000 * kMs, kMs, Discontinuity::Forward},
  };
  for (const JumpCase& c : cases) {
    SCOPED_TRACE(c.name);
    EXPECT_EQ(discontinuity(c.latest_ns, c.time_ns, c.cycle_ns, kPause), c.expected);
  }
}

struct SegmentCase {
  const char* name;
  std::vector<std::int64_t> times_ns;  // frames 1, 2, ...
  std::optional<std::int64_t> cycle_ns;
  std::vector<CaptureSegment> expected;
};

TEST(SegmentTracker, ListsTheSegmentsAndRestartsTheClock) {
  const SegmentCase cases[] = {
      {"no frame", {}, kMs, {}},
      {"one frame", {5 * kMs}, kMs, {{1, 1, 5 * kMs, 5 * kMs}}},
      {"steady", {0, kMs, 2 * kMs, 3 * kMs}, kMs, {{1, 4, 0, 3 * kMs}}},
      {"a small back-step: one segment, its end the latest time",
       {0, kMs, 2 * kMs, 2 * kMs - 5 * kUs},
       kMs,
       {{1, 4, 0, 2 * kMs}}},
      {"two recordings appended",
       {0, kMs, 2 * kMs, 0, kMs},
       kMs,
       {{1, 3, 0, 2 * kMs}, {4, 5, 0, kMs}}},
      {"paused for an hour",
       {0, kMs, 3600'000 * kMs, 3600'001 * kMs},
       kMs,
       {{1, 2, 0, kMs}, {3, 4, 3600'000 * kMs, 3600'001 * kMs}}},
      {"appended, the second part earlier",
       {100 * kMs, 101 * kMs, 0, kMs, 2 * kMs},
       kMs,
       {{1, 2, 100 * kMs, 101 * kMs}, {3, 5, 0, 2 * kMs}}},
  };
  for (const SegmentCase& c : cases) {
    SCOPED_TRACE(c.name);
    SegmentTracker tracker(kPause);
    std::vector<std::uint64_t> starts;
    for (std::size_t i = 0; i < c.times_ns.size(); ++i) {
      if (tracker.onFrame(i + 1, c.times_ns[i], c.cycle_ns)) starts.push_back(i + 1);
      EXPECT_GE(tracker.now(), c.times_ns[i]) << "the segment's clock never lags its frames";
    }
    ASSERT_EQ(tracker.segments().size(), c.expected.size());
    EXPECT_EQ(tracker.count(), c.expected.size());
    std::vector<std::uint64_t> expected_starts;
    for (std::size_t s = 0; s < c.expected.size(); ++s) {
      const CaptureSegment& got = tracker.segments()[s];
      const CaptureSegment& want = c.expected[s];
      EXPECT_EQ(got.first_frame, want.first_frame) << "segment " << s;
      EXPECT_EQ(got.last_frame, want.last_frame) << "segment " << s;
      EXPECT_EQ(got.start_ns, want.start_ns) << "segment " << s;
      EXPECT_EQ(got.end_ns, want.end_ns) << "segment " << s;
      if (s > 0) expected_starts.push_back(want.first_frame);
    }
    EXPECT_EQ(starts, expected_starts) << "onFrame is true on each later segment's first frame";
  }
}

TEST(SegmentTracker, ListsAtMostKMaxListedAndCountsTheRest) {
  SegmentTracker tracker(kPause);
  const std::uint64_t total = SegmentTracker::kMaxListed + 5;
  for (std::uint64_t i = 0; i < total; ++i) {
    tracker.onFrame(2 * i + 1, 0, kMs);  // each segment: two frames, the first going back
    tracker.onFrame(2 * i + 2, 10 * kMs, kMs);
  }
  EXPECT_EQ(tracker.count(), total);
  ASSERT_EQ(tracker.segments().size(), SegmentTracker::kMaxListed);
  EXPECT_EQ(tracker.segments().back().last_frame, 2 * SegmentTracker::kMaxListed);
}

}  // namespace
}  // namespace ncservo
