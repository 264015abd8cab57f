// The bus rules on cyclic traffic without servos (docs/timing.md "Which frames"): a TwinCAT-like
// I/O frame (LRD 0x09000000, 1 byte; LRW 0x01000000, 20 bytes), a master copy and a returned copy
// per 1 ms cycle, through the Validator with no layout at all.
#include "ncservo/model/bus_model.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/rules/validator.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::Dg;
using test::FrameBuilder;

constexpr std::int64_t kCycleNs = 1'000'000;
constexpr std::int64_t kEpochNs = 1'700'000'000'000'000'000;
constexpr std::uint16_t kLrdWkc = 1, kLrwWkc = 6;
constexpr int kCycles = 30;
constexpr int kNone = -1;

struct Row {
  std::string name;
  int lost_cycle = kNone;  // neither copy captured
  int unreturned = kNone;  // the returned copy missing
  int wrong_wkc = kNone;   // the LRW returned with WKC 4
  int one_offs = 0;        // frames of other logical datagrams, each once, before cycle 0
  RuleId rule = RuleId::Com001;
  std::vector<std::uint64_t> frames;  // where `rule` is reported ({}: nothing at all)
  std::string message;                // part of the first finding's message
  std::uint64_t cycles = kCycles;
  std::uint64_t judged_frames = 2 * kCycles;  // frames of each judged datagram
  int master_missing = kNone;  // only the returned copy captured: capture loss, not bus loss
  int slow_every = 0;          // a second task's frame (LRW 0x03000000) every this many cycles
  int run = kCycles;           // cycles of the fast frame
  std::uint64_t master_copies_missing = 0;
  std::uint64_t returned_copies_missing = 0;
};

// Frame numbers when nothing before the cycle was dropped and no one-off frame came first.
constexpr std::uint64_t masterOf(int cycle) {
  return 2 * static_cast<std::uint64_t>(cycle) + 1;
}

const Row kRows[] = {
    {"clean", kNone, kNone, kNone, 0, RuleId::Com001, {}, ""},
    {"COM-001 against the usual WKC",
     kNone,
     kNone,
     12,
     0,
     RuleId::Com001,
     {masterOf(12) + 1},
     "LRW at 0x01000000 (20 bytes) returned with WKC 4, expected 6"},
    {"COM-002 one master copy after a lost cycle",
     12,
     kNone,
     kNone,
     0,
     RuleId::Com002,
     {masterOf(14) - 2},
     "1 cycle lost",
     kCycles - 1,
     2 * (kCycles - 1)},
    {"COM-004 names the first datagram",
     kNone,
     12,
     kNone,
     0,
     RuleId::Com004,
     {masterOf(13) - 1},
     "the master frame 25 (LRD at 0x09000000, 1 byte, and 1 more datagram) was not returned",
     kCycles,
     2 * kCycles - 1,
     kNone,
     0,
     kCycles,
     0,
     1},
    {"a returned copy whose master copy the capture missed: its cycle ran",
     kNone,
     kNone,
     kNone,
     0,
     RuleId::Com002,
     {},
     "",
     kCycles,
     2 * kCycles - 1,
     12,
     0,
     kCycles,
     1,
     0},
    {"two missing master copies in a row",
     kNone,
     kNone,
     kNone,
     0,
     RuleId::Com002,
     {},
     "",
     kCycles,
     2 * kCycles - 2,
     20,
     0,
     kCycles,
     2,
     0},
    {"a 10 ms task beside the 1 ms one: each frame its own clock",
     kNone,
     kNone,
     kNone,
     0,
     RuleId::Com002,
     {},
     "",
     200,
     400,
     kNone,
     10,
     200},
    {"one-off frames give way to cyclic ones",
     kNone,
     kNone,
     kNone,
     static_cast<int>(BusModel::kMaxCyclicFrames) + 4,
     RuleId::Com001,
     {},
     ""},
};

class ServolessBus : public ::testing::TestWithParam<Row> {};

TEST_P(ServolessBus, JudgesCyclicDatagrams) {
  const Row& row = GetParam();
  DecoderOptions options;
  options.default_layout = false;
  Validator validator(options, RuleSettings{});
  std::uint64_t frame = 0;
  std::vector<Finding> findings;
  auto feed = [&](const Bytes& bytes, std::int64_t time_ns) {
    const test::Walked w = test::walk(bytes, bytes.size());
    validator.onFrame(++frame, time_ns, *w.frame, w.reader());
    findings.insert(findings.end(), validator.findings().begin(), validator.findings().end());
  };
  // The master numbers its datagrams anew each cycle, so that a master copy that follows an
  // unreturned one is not taken for its returned copy (docs/protocol.md §8).
  auto cyclic = [](int cycle, bool returned, std::uint16_t lrw_wkc) {
    const auto index = static_cast<std::uint8_t>(2 * cycle);
    return FrameBuilder()
        .add(Dg(ecat::kLrd, index, 0x09000000, Bytes(1, 0), returned ? kLrdWkc : 0))
        .add(Dg(ecat::kLrw, static_cast<std::uint8_t>(index + 1), 0x01000000, Bytes(20, 0),
                returned ? lrw_wkc : 0))
        .bytes();
  };
  std::int64_t t = kEpochNs;
  for (int i = 0; i < row.one_offs; ++i) {
    feed(FrameBuilder()
             .add(Dg(ecat::kLrd, 0, 0x02000000 + static_cast<std::uint32_t>(i), Bytes(2, 0), 0))
             .bytes(),
         t - kCycleNs + i);
  }
  auto slow = [](int cycle, bool returned) {
    return FrameBuilder()
        .add(Dg(ecat::kLrw, static_cast<std::uint8_t>(cycle), 0x03000000, Bytes(8, 0),
                returned ? 3 : 0))
        .bytes();
  };
  // The second master copy of "two missing" is missed too.
  const auto master_missing = [&](int c) {
    return c == row.master_missing ||
           (row.name.rfind("two", 0) == 0 && c == row.master_missing + 1);
  };
  for (int c = 0; c < row.run; ++c, t += kCycleNs) {
    if (c == row.lost_cycle) continue;
    if (!master_missing(c)) feed(cyclic(c, false, 0), t);
    if (c != row.unreturned) feed(cyclic(c, true, c == row.wrong_wkc ? 4 : kLrwWkc), t + 20'000);
    if (row.slow_every > 0 && c % row.slow_every == 0) {
      feed(slow(c, false), t + 500'000);
      feed(slow(c, true), t + 520'000);
    }
  }

  std::vector<std::uint64_t> reported;
  for (const Finding& f : findings) {
    EXPECT_EQ(f.axis, std::nullopt) << f.message;
    if (f.rule == row.rule)
      reported.push_back(f.at.frame - static_cast<std::uint64_t>(row.one_offs));
  }
  EXPECT_EQ(reported, row.frames);
  if (row.frames.empty()) {
    EXPECT_TRUE(findings.empty()) << findings.front().message;
  } else {
    ASSERT_FALSE(findings.empty());
    EXPECT_NE(findings.front().message.find(row.message), std::string::npos)
        << findings.front().message;
  }
  EXPECT_EQ(validator.cycles(), row.cycles);
  EXPECT_EQ(validator.bus().masterCopiesMissing(), row.master_copies_missing);
  EXPECT_EQ(validator.bus().returnedCopiesMissing(), row.returned_copies_missing);
  const std::vector<CyclicDatagram> judged = validator.bus().cyclicDatagrams();
  ASSERT_EQ(judged.size(), row.slow_every > 0 ? 3u : 2u);
  EXPECT_EQ(judged[0].command, ecat::kLrd);
  EXPECT_EQ(judged[0].address, 0x09000000u);
  EXPECT_EQ(judged[0].length, 1);
  EXPECT_EQ(judged[1].command, ecat::kLrw);
  EXPECT_EQ(judged[1].length, 20);
  EXPECT_EQ(judged[0].frames, row.judged_frames);
  EXPECT_EQ(judged[1].frames, row.judged_frames);
  const TimingSummary timing = validator.bus().timing().summary();
  ASSERT_TRUE(timing.cycle);
  EXPECT_EQ(validator.bus().unfollowedFrames(), 0u);
  const std::vector<CyclicFrameSummary> frames = validator.bus().cyclicFrames();
  ASSERT_EQ(frames.size(), row.slow_every > 0 ? 2u : 1u);
  EXPECT_EQ(frames[0].cycle_ns, kCycleNs);
  EXPECT_EQ(frames[0].cycles, row.cycles);
  if (row.slow_every > 0) {
    EXPECT_EQ(frames[1].cycle_ns, kCycleNs * row.slow_every);
    EXPECT_EQ(frames[1].cycles, static_cast<std::uint64_t>(row.run / row.slow_every));
  } else {
    EXPECT_EQ(timing.cycle->median_ns, kCycleNs);
  }
}

INSTANTIATE_TEST_SUITE_P(Rows, ServolessBus, ::testing::ValuesIn(kRows), test::rowName<Row>);

}  // namespace
}  // namespace ncservo
