// The capture pipeline as every command drives it: the layout decided before the first frame is
// delivered, the time window's frames judged and the others layout-only, and the end of the
// capture judged once, with its findings through the same callback as every frame's.
#include "ncservo/pipeline/capture_pipeline.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "ncservo/rules/rules.hpp"
#include "ncservo/sim/simulator.hpp"
#include "ncservo/wire/ethercat.hpp"

namespace ncservo {
namespace {

struct Recorded {
  std::vector<std::uint8_t> bytes;
  std::int64_t time_ns;
};

// Two axes of commissioning, one second.
std::vector<Recorded> simulated() {
  sim::SimOptions options;
  options.axes = 2;
  options.duration_s = 1.0;
  EXPECT_TRUE(sim::resolveOptions(options));
  std::vector<Recorded> frames;
  sim::Simulator simulator(options);
  EXPECT_TRUE(simulator.run([&](const sim::SimFrame& f) {
    frames.push_back({std::vector<std::uint8_t>(f.data, f.data + f.size), f.time_ns});
    return true;
  }));
  return frames;
}

// What the sinks saw, in order.
struct Seen {
  int starts = 0;
  bool started_before_frames = true;
  std::vector<std::uint64_t> judged, layout_only;
  std::vector<Finding> findings;
  CapturePipeline::Sinks sinks() {
    return {[this](const DecoderOptions&) { ++starts; },
            [this](const PipelineFrame& f) {
              started_before_frames = started_before_frames && starts == 1;
              EXPECT_NE(f.judged, nullptr);
              judged.push_back(f.number);
            },
            [this](const PipelineFrame& f) { layout_only.push_back(f.number); },
            [this](const std::vector<Finding>& found) {
              findings.insert(findings.end(), found.begin(), found.end());
            },
            nullptr};
  }
};

void feed(CapturePipeline& pipeline, const std::vector<Recorded>& frames) {
  std::uint64_t number = 0;
  for (const Recorded& f : frames) {
    CaptureRecord record;
    record.frame = ++number;
    record.time_ns = f.time_ns;
    record.data = f.bytes.data();
    record.captured = record.original = f.bytes.size();
    pipeline.onRecord(LinkType::Ethernet, record);
  }
  pipeline.finish();
}

TEST(CapturePipeline, StartsOnceEvenWithoutAFrame) {
  Seen seen;
  CapturePipeline pipeline({DecoderOptions{}, RuleSettings{}, TimeWindow{}, TimestampMode::Auto});
  pipeline.setSinks(seen.sinks());
  pipeline.finish();
  EXPECT_EQ(seen.starts, 1);
  EXPECT_NE(pipeline.validator(), nullptr);
  CapturePipeline unjudged({DecoderOptions{}, std::nullopt, TimeWindow{}, TimestampMode::Auto});
  unjudged.finish();
  EXPECT_EQ(unjudged.validator(), nullptr);
}

TEST(CapturePipeline, TheTimeWindowsFramesAreJudgedTheOthersShowTheLayout) {
  const std::vector<Recorded> frames = simulated();
  Seen seen;
  const TimeWindow window{500'000'000, std::nullopt};
  CapturePipeline pipeline({DecoderOptions{}, RuleSettings{}, window, TimestampMode::Capture});
  pipeline.setSinks(seen.sinks());
  feed(pipeline, frames);
  EXPECT_EQ(seen.starts, 1);
  EXPECT_TRUE(seen.started_before_frames);
  ASSERT_FALSE(seen.judged.empty());
  ASSERT_FALSE(seen.layout_only.empty());
  EXPECT_EQ(seen.judged.size() + seen.layout_only.size(), frames.size());
  EXPECT_EQ(pipeline.run().in_window, seen.judged.size());
  EXPECT_LT(seen.layout_only.back(), seen.judged.front());
  for (std::size_t i = 1; i < seen.judged.size(); ++i) {
    EXPECT_LT(seen.judged[i - 1], seen.judged[i]);  // capture order, the held frames first
  }
}

// docs/rules.md#com-002: a gap whose next cycle never came is judged at the end of the capture,
// on its last frame.
TEST(CapturePipeline, TheEndOfTheCaptureJudgesAGapInTheLastCycle) {
  std::vector<Recorded> frames = simulated();
  ASSERT_GT(frames.size(), 20u);
  frames.erase(frames.end() - 12, frames.end() - 2);  // five cycles before the last
  Seen seen;
  CapturePipeline pipeline(
      {DecoderOptions{}, RuleSettings{}, TimeWindow{}, TimestampMode::Capture});
  pipeline.setSinks(seen.sinks());
  feed(pipeline, frames);
  std::vector<Finding> gaps;
  for (const Finding& f : seen.findings) {
    if (f.rule == RuleId::Com002) gaps.push_back(f);
  }
  ASSERT_EQ(gaps.size(), 1u);
  EXPECT_EQ(gaps[0].at.frame, frames.size());
  EXPECT_NE(gaps[0].message.find("the capture ends before the next cycle"), std::string::npos)
      << gaps[0].message;
}

}  // namespace
}  // namespace ncservo
