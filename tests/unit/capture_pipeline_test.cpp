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
#include "row_name.hpp"

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
    record.link = LinkType::Ethernet;
    pipeline.onRecord(record);
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

// Records of other interfaces beside the bus's (docs/cli.md#interfaces): each counted under its
// own interface and walked from its own link type, and the bus judged as without them.
struct Fed {
  std::vector<std::uint8_t> bytes;
  std::int64_t time_ns;
  std::uint32_t interface;
  int link_type;
};

// An ARP request behind a Linux cooked (SLL) header, as `tcpdump -i any` records one.
std::vector<std::uint8_t> cookedArp() {
  std::vector<std::uint8_t> bytes = {0, 0, 0, 1, 0, 6, 2, 0, 0, 0, 0, 1, 0, 0, 0x08, 0x06};
  bytes.resize(bytes.size() + 28, 0x11);
  return bytes;
}

struct InterfacesRow {
  const char* name;
  // The records fed, from the bus's frames.
  std::vector<Fed> (*records)(const std::vector<Recorded>& bus);
  // What result() lists, from how many frames the bus had.
  std::vector<CaptureInterface> (*want)(std::uint64_t bus);
  std::uint64_t omitted = 0;  // records of interfaces not listed
  bool judged = true;         // the bus judged as on its own; else nothing, for `reason`
  const char* reason = "";
};

std::vector<Fed> busOn(const std::vector<Recorded>& bus, std::uint32_t interface, int link_type) {
  std::vector<Fed> fed;
  for (const Recorded& r : bus) fed.push_back({r.bytes, r.time_ns, interface, link_type});
  return fed;
}

// After every `every`th frame of the bus on interface 0, one record of `interface`.
std::vector<Fed> besideTheBus(const std::vector<Recorded>& bus, std::size_t every,
                              std::uint32_t interface, int link_type, bool copy_of_the_bus) {
  std::vector<Fed> fed;
  for (std::size_t i = 0; i < bus.size(); ++i) {
    fed.push_back({bus[i].bytes, bus[i].time_ns, 0, 1});
    if ((i + 1) % every != 0) continue;
    fed.push_back({copy_of_the_bus ? bus[i].bytes : cookedArp(), bus[i].time_ns + 1000, interface,
                   link_type});
  }
  return fed;
}

const InterfacesRow kInterfacesRows[] = {
    {"an_office_port_in_linux_cooked",
     [](const std::vector<Recorded>& bus) { return besideTheBus(bus, 5, 1, 113, false); },
     [](std::uint64_t bus) {
       return std::vector<CaptureInterface>{{0, 1, bus, true}, {1, 113, bus / 5, false}};
     }},
    {"ethercat_on_a_link_type_not_walked",
     [](const std::vector<Recorded>& bus) { return besideTheBus(bus, 3, 7, 147, true); },
     [](std::uint64_t bus) {
       return std::vector<CaptureInterface>{{0, 1, bus, true}, {7, 147, bus / 3, false}};
     }},
    {"more_interfaces_than_listed",
     [](const std::vector<Recorded>& bus) {
       std::vector<Fed> fed = busOn(bus, 0, 1);
       for (std::uint32_t i = 1; i <= 70; ++i) {
         fed.insert(fed.begin() + i * 2, {cookedArp(), fed[i * 2 - 1].time_ns + 1, i, 113});
       }
       return fed;
     },
     [](std::uint64_t bus) {
       std::vector<CaptureInterface> listed{{0, 1, bus, true}};
       for (std::uint32_t i = 1; i < CapturePipeline::kMaxInterfaces; ++i) {
         listed.push_back({i, 113, 1, false});
       }
       return listed;
     },
     70 - (CapturePipeline::kMaxInterfaces - 1)},
    {"only_a_link_type_not_walked",
     [](const std::vector<Recorded>& bus) { return busOn(bus, 0, 147); },
     [](std::uint64_t bus) {
       return std::vector<CaptureInterface>{{0, 147, bus, false}};
     },
     0, false,
     "no frame of a link type ncservo reads (Ethernet, Linux cooked SLL and SLL2): the capture's "
     "link type is 147"},
};

class CapturePipelineInterfaces : public ::testing::TestWithParam<InterfacesRow> {};

TEST_P(CapturePipelineInterfaces, CountsEachAndJudgesTheBusAlone) {
  const InterfacesRow& row = GetParam();
  std::vector<Recorded> bus = simulated();
  ASSERT_GT(bus.size(), 200u);
  bus.erase(bus.begin() + 100, bus.begin() + 110);  // a gap: a finding to compare
  const auto judge = [](const std::vector<Fed>& fed, std::vector<Finding>& findings) {
    Seen seen;
    CapturePipeline pipeline(
        {DecoderOptions{}, RuleSettings{}, TimeWindow{}, TimestampMode::Capture});
    pipeline.setSinks(seen.sinks());
    std::uint64_t number = 0;
    for (const Fed& f : fed) {
      CaptureRecord record;
      record.frame = ++number;
      record.time_ns = f.time_ns;
      record.data = f.bytes.data();
      record.captured = record.original = f.bytes.size();
      record.interface = f.interface;
      record.link_type = f.link_type;
      record.link = linkTypeFromDlt(f.link_type);
      pipeline.onRecord(record);
    }
    pipeline.finish();
    findings = seen.findings;
    return pipeline.result();
  };
  std::vector<Finding> alone, beside;
  const CaptureResult reference = judge(busOn(bus, 0, 1), alone);
  const std::vector<Fed> fed = row.records(bus);
  const CaptureResult result = judge(fed, beside);
  EXPECT_EQ(result.frames, fed.size());
  const std::vector<CaptureInterface> want = row.want(bus.size());
  ASSERT_EQ(result.interfaces.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(result.interfaces[i].id, want[i].id);
    EXPECT_EQ(result.interfaces[i].link_type, want[i].link_type);
    EXPECT_EQ(result.interfaces[i].frames, want[i].frames);
    EXPECT_EQ(result.interfaces[i].ethercat, want[i].ethercat);
  }
  EXPECT_EQ(result.interface_records_omitted, row.omitted);
  if (!row.judged) {
    EXPECT_FALSE(result.coverage.complete());
    EXPECT_EQ(result.coverage.reason, row.reason);
    EXPECT_TRUE(beside.empty());
    return;
  }
  ASSERT_FALSE(alone.empty());
  ASSERT_EQ(beside.size(), alone.size());
  for (std::size_t i = 0; i < alone.size(); ++i) {
    SCOPED_TRACE(alone[i].message);
    EXPECT_EQ(beside[i].rule, alone[i].rule);
    EXPECT_EQ(beside[i].axis, alone[i].axis);
    EXPECT_EQ(beside[i].at.time_ns, alone[i].at.time_ns);
  }
  EXPECT_EQ(result.cycles, reference.cycles);
  EXPECT_EQ(result.coverage.complete(), reference.coverage.complete());
}

INSTANTIATE_TEST_SUITE_P(Rows, CapturePipelineInterfaces, ::testing::ValuesIn(kInterfacesRows),
                         test::rowName<InterfacesRow>);

}  // namespace
}  // namespace ncservo
