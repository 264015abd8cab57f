// The model of one axis (axis_model.hpp): signal levels and edges, the valid enable of
// docs/protocol.md §2, the error history of §7 (newest first, at most eight), the state timeline
// of §6, the Servo_Ready_Mode of §5, and the telegram-failure counters (COM-*). One row per case.
#include "ncservo/model/axis_model.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <iterator>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/pdo.hpp"
#include "validator_driver.hpp"

namespace ncservo {
namespace {

using test::kClear;
using test::kClearAck;
using test::kEcatTErr;
using test::kEncoderErr;
using test::kEpochNs;
using test::kMs;
using test::kScwArmed;
using test::kScwOff;
using test::kScwRunning;
using test::kScwSe3;
using test::kSswNone;
using test::kSswReady;
using test::kSswRunning;
using test::kSummary;
using test::kZRequest;

PdoValues pdo(std::optional<std::uint32_t> scw, std::optional<std::uint32_t> ssw,
              std::uint32_t sew = 0) {
  PdoValues v;
  if (scw) {
    v.raw[static_cast<std::size_t>(Word::Scw)] = *scw;
    v.has_rx = true;
  }
  if (ssw) {
    v.raw[static_cast<std::size_t>(Word::Ssw)] = *ssw;
    v.raw[static_cast<std::size_t>(Word::Sew)] = sew;
    v.has_tx = true;
  }
  return v;
}
Stamp stamp(std::uint64_t frame) {
  return Stamp{frame, kEpochNs + static_cast<std::int64_t>(frame) * kMs};
}

// docs/protocol.md §4 and §7: each SEW cause bit, its display code and its CANopen-style code.
struct CauseRow {
  const char* field;
  unsigned bit;
  const char* display;
  std::uint16_t canopen;
  const char* text;  // as the reports name it: the E-number and the bit's name
};
constexpr CauseRow kCauseRows[] = {
    {"ncservo.sew.encoder", 1, "E01", 0x7305, "E01 EncoderErr"},
    {"ncservo.sew.i2t_endat", 2, "E19", 0x4200, "E19 I2t_Endat"},
    {"ncservo.sew.ecat_config", 3, "E14", 0x8100, "E14 ECatConfigError"},
    {"ncservo.sew.bus_voltage", 5, "E05", 0x3100, "E05 BVErr"},
    {"ncservo.sew.current", 6, "E06", 0x2300, "E06 CurrErr"},
    {"ncservo.sew.current_offset", 7, "E07", 0x2300, "E07 CURROErr"},
    {"ncservo.sew.hall", 8, "E08", 0x7306, "E08 HallErr"},
    {"ncservo.sew.hall_sequence", 9, "HallSErr", 0x7306, "HallSErr"},
    {"ncservo.sew.servo_runtime", 10, "SRTErr", 0x6010, "SRTErr"},
    {"ncservo.sew.can1_timeout", 11, "CAN1TErr", 0x8130, "CAN1TErr"},
    {"ncservo.sew.can2_timeout", 12, "CAN2TErr", 0x8130, "CAN2TErr"},
    {"ncservo.sew.can1_hw", 13, "CAN1HErr", 0x8100, "CAN1HErr"},
    {"ncservo.sew.can2_hw", 14, "CAN2HErr", 0x8100, "CAN2HErr"},
    {"ncservo.sew.ecat_timeout", 15, "E15", 0x8130, "E15 ECatTErr"},
    {"ncservo.sew.pdpint", 16, "E16", 0x2300, "E16 PDPINT"},
    {"ncservo.sew.param_checksum", 17, "E30", 0x6320, "E30 PTBLCHKSErr"},
    {"ncservo.sew.program_checksum", 18, "PRGCHKSErr", 0x6100, "PRGCHKSErr"},
    {"ncservo.sew.following", 19, "E09", 0x8611, "E09 FollowerErr"},
    {"ncservo.sew.overload", 20, "E20", 0x2300, "E20 OverLoad"},
    {"ncservo.sew.flash", 21, "E32", 0x7600, "E32 SFlashErr"},
    {"ncservo.sew.ecat_watchdog", 22, "E31", 0x8100, "E31 ECatWatchDog"},
    {"ncservo.sew.overspeed", 23, "E11", 0x8400, "E11 OverSpeed"},
    {"ncservo.sew.current_symmetry", 24, "E12", 0x2300, "E12 CurrDiffErr"},
};

TEST(AxisModelErrorHistory, EachCauseBitGivesItsCodes) {
  ASSERT_EQ(std::size(kCauseRows), kSewCauses.size());
  std::uint32_t all = 0;
  for (const CauseRow& row : kCauseRows) {
    SCOPED_TRACE(row.field);
    EXPECT_EQ(field(row.field).mask, std::uint64_t{1} << row.bit);
    all |= 1u << row.bit;
    AxisModel axis(0, std::nullopt);
    axis.observe(pdo(kScwOff, kSswNone), stamp(1));
    axis.observe(pdo(kScwOff, kSswNone, kSummary | (1u << row.bit)), stamp(2));
    ASSERT_EQ(axis.errorHistory().size(), 1u);
    const ErrorHistoryEntry& entry = axis.errorHistory()[0];
    ASSERT_NE(entry.cause, nullptr);
    EXPECT_EQ(entry.cause->mask, 1u << row.bit);
    EXPECT_STREQ(entry.cause->display, row.display);
    EXPECT_EQ(entry.cause->canopen, row.canopen);
    EXPECT_EQ(sewCauseText(*entry.cause), row.text);
    EXPECT_EQ(entry.at.frame, 2u);
    EXPECT_EQ(entry.at.time_ns, stamp(2).time_ns);
  }
  EXPECT_EQ(all, kSewCauseMask);
}

TEST(AxisModelErrorHistory, NewestFirstAtMostEight) {
  AxisModel axis(0, std::nullopt);
  axis.observe(pdo(kScwOff, kSswNone), stamp(1));
  // Ten causes rise one after the other, each in its own frame (frames 2..11).
  std::uint32_t sew = kSummary;
  for (std::size_t i = 0; i < 10; ++i) {
    sew |= 1u << kCauseRows[i].bit;
    axis.observe(pdo(kScwOff, kSswNone, sew), stamp(2 + i));
  }
  const auto& history = axis.errorHistory();
  ASSERT_EQ(history.size(), AxisModel::kErrorHistoryDepth);
  for (std::size_t i = 0; i < history.size(); ++i) {
    SCOPED_TRACE("entry " + std::to_string(i));
    const CauseRow& row = kCauseRows[9 - i];  // newest first: frame 11's cause leads
    EXPECT_EQ(history[i].cause->mask, 1u << row.bit);
    EXPECT_EQ(history[i].at.frame, 11u - i);
  }
  // A cause that stays set makes no entry; one that falls and rises again makes a new one.
  axis.observe(pdo(kScwOff, kSswNone, sew), stamp(12));
  EXPECT_EQ(history.front().at.frame, 11u);
  axis.observe(pdo(kScwOff, kSswNone, sew & ~kEncoderErr), stamp(13));
  axis.observe(pdo(kScwOff, kSswNone, sew), stamp(14));
  EXPECT_EQ(history.front().at.frame, 14u);
  EXPECT_EQ(history.front().cause->mask, kEncoderErr);
  EXPECT_EQ(history.size(), AxisModel::kErrorHistoryDepth);
}

TEST(AxisModelErrorHistory, SummaryAndReservedBitsMakeNoEntry) {
  AxisModel axis(0, std::nullopt);
  axis.observe(pdo(kScwOff, kSswNone), stamp(1));
  axis.observe(pdo(kScwOff, kSswNone, kSummary | 0x10 | 0xFE000000u), stamp(2));
  EXPECT_TRUE(axis.errorHistory().empty());
}

// docs/protocol.md §6: the drive's states and transition names.
struct TimelineStep {
  const char* name;
  std::uint32_t scw;
  std::uint32_t ssw;
  std::uint32_t sew;
  std::optional<DriveState> change;  // a new timeline entry with this state, or none
  const char* transition;            // its name, or nullptr
};
const TimelineStep kTimeline[] = {
    {"first: ready to switch on", kScwArmed, kSswReady, 0, DriveState::ReadyToSwitchOn, nullptr},
    {"legal enable, ServoEn rises", kScwRunning, kSswRunning, 0, DriveState::ControlActive,
     "ENABLE OPERATION"},
    {"unchanged", kScwRunning, kSswRunning, 0, std::nullopt, nullptr},
    {"error while enabled", kScwRunning, kSswRunning, kSummary | kEncoderErr,
     DriveState::FaultReactionActive, "FAULT REACTION ACTIVE"},
    {"drive disables in error", kScwOff, kSswNone, kSummary | kEncoderErr, DriveState::Error,
     "FAULT"},
    {"error cleared", kScwOff | kClear, kSswReady | kClearAck, 0, DriveState::ReadyToSwitchOn,
     "FAULT RESET"},
    {"armed", kScwArmed, kSswReady, 0, std::nullopt, nullptr},
    {"enabled again", kScwRunning, kSswRunning, 0, DriveState::ControlActive, "ENABLE OPERATION"},
    {"emergency ramp", 0x402, kSswRunning, 0, DriveState::DriveStop, nullptr},
    {"running", kScwRunning, kSswRunning, 0, DriveState::ControlActive, nullptr},
    {"disabled", kScwOff, kSswReady, 0, DriveState::ReadyToSwitchOn, "DISABLE OPERATION"},
    {"illegal enable 0x0 -> 0x2, ServoEn rises", kScwRunning, kSswRunning, 0,
     DriveState::ControlActive, nullptr},
    {"power stage off", kScwRunning, 0x03, 0, DriveState::EnabledPowerStageOff, nullptr},
    {"disabled, power stage on", kScwOff, 0x82, 0, DriveState::SwitchedOn, "DISABLE OPERATION"},
    {"error while disabled", kScwOff, kSswNone, kSummary | kEncoderErr, DriveState::Error, "FAULT"},
    {"not ready", kScwOff, kSswNone, 0, DriveState::NotReadyToSwitchOn, "FAULT RESET"},
};

TEST(AxisModelTimeline, StatesAndTransitionNames) {
  AxisModel axis(0, std::nullopt);
  std::size_t entries = 0;
  std::uint64_t frame = 0;
  for (const TimelineStep& step : kTimeline) {
    SCOPED_TRACE(step.name);
    axis.observe(pdo(step.scw, step.ssw, step.sew), stamp(++frame));
    if (!step.change) {
      EXPECT_EQ(axis.timeline().size(), entries);
      continue;
    }
    ASSERT_EQ(axis.timeline().size(), ++entries);
    const StateChange& change = axis.timeline().back();
    EXPECT_EQ(change.state, *step.change);
    EXPECT_EQ(axis.state(), step.change);
    EXPECT_EQ(change.at.frame, frame);
    if (step.transition == nullptr) {
      EXPECT_EQ(change.transition, nullptr) << change.transition;
    } else {
      ASSERT_NE(change.transition, nullptr);
      EXPECT_STREQ(change.transition, step.transition);
    }
  }
}

TEST(AxisModelTimeline, OutputsAloneGiveNoState) {
  AxisModel axis(0, std::nullopt);
  axis.observe(pdo(kScwRunning, std::nullopt), stamp(1));
  EXPECT_FALSE(axis.state().has_value());
  EXPECT_TRUE(axis.timeline().empty());
}

// docs/rules.md#rdy-001: configured, or inferred from the first observation with ServoEn 0 and no
// error (RDY 1 -> mode 0, RDY 0 -> mode 1).
struct ReadyModeCase {
  const char* name;
  std::optional<int> configured;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> inputs;  // (SSW, SEW) per observation
  std::optional<int> mode;
};
const std::vector<ReadyModeCase>& readyModeCases() {
  static const std::vector<ReadyModeCase> cases = {
      {"disabled, ready", std::nullopt, {{kSswReady, 0}}, 0},
      {"disabled, not ready", std::nullopt, {{kSswNone, 0}}, 1},
      {"enabled first: unknown", std::nullopt, {{kSswRunning, 0}}, std::nullopt},
      {"enabled, then disabled and ready", std::nullopt, {{kSswRunning, 0}, {kSswReady, 0}}, 0},
      {"in error: unknown", std::nullopt, {{kSswNone, kSummary | kEncoderErr}}, std::nullopt},
      {"in error, then cleared, not ready",
       std::nullopt,
       {{kSswReady, kSummary | kEncoderErr}, {kSswNone, 0}},
       1},
      {"inferred once, from the first such observation",
       std::nullopt,
       {{kSswReady, 0}, {kSswNone, 0}},
       0},
      {"configured 1 is kept", 1, {{kSswReady, 0}}, 1},
      {"configured 0 is kept", 0, {{kSswNone, 0}}, 0},
  };
  return cases;
}

TEST(AxisModelReadyMode, ConfiguredOrInferred) {
  for (const ReadyModeCase& c : readyModeCases()) {
    SCOPED_TRACE(c.name);
    AxisModel axis(0, c.configured);
    EXPECT_EQ(axis.readyModeConfigured(), c.configured.has_value());
    std::uint64_t frame = 0;
    for (const auto& [ssw, sew] : c.inputs) axis.observe(pdo(kScwOff, ssw, sew), stamp(++frame));
    EXPECT_EQ(axis.readyMode(), c.mode);
  }
}

TEST(AxisModelReadyMode, ExpectedReadyFollowsTheTable) {
  struct Row {
    int mode;
    std::uint32_t ssw;  // ServoEn in bit 0
    std::uint32_t sew;
    bool ready;
  };
  // docs/protocol.md §5.
  const Row rows[] = {
      {0, 0x0, 0, true},  {0, 0x1, 0, true},    {0, 0x0, 0x3, false}, {0, 0x1, 0x3, false},
      {1, 0x0, 0, false}, {1, 0x0, 0x3, false}, {1, 0x1, 0, true},    {1, 0x1, 0x3, false},
  };
  for (const Row& row : rows) {
    SCOPED_TRACE("mode " + std::to_string(row.mode) + " SSW " + std::to_string(row.ssw) + " SEW " +
                 std::to_string(row.sew));
    AxisModel axis(0, row.mode);
    EXPECT_FALSE(axis.expectedReady().has_value()) << "no inputs yet";
    axis.observe(pdo(kScwOff, row.ssw, row.sew), stamp(1));
    EXPECT_EQ(axis.expectedReady(), row.ready);
  }
  AxisModel unknown(0, std::nullopt);
  unknown.observe(pdo(kScwRunning, kSswRunning), stamp(1));
  EXPECT_FALSE(unknown.expectedReady().has_value());
}

TEST(AxisModelCounters, TotalFailuresSaturateAndResetOnEnteringOp) {
  AxisModel axis(0, std::nullopt);
  axis.cycleFailed(true, 65534, stamp(1));
  EXPECT_EQ(axis.totalFailures(), 65534u);
  axis.cycleFailed(false, 1, stamp(2));
  EXPECT_EQ(axis.totalFailures(), AxisModel::kFailureCounterMax);
  axis.cycleFailed(true, 10, stamp(3));
  EXPECT_EQ(axis.totalFailures(), 65535u);
  axis.cycleOk(stamp(4));
  EXPECT_EQ(axis.totalFailures(), 65535u) << "a good cycle does not reset the total";
  EXPECT_EQ(axis.consecutiveFailed(), 0u);
  axis.enteredOp();
  EXPECT_EQ(axis.totalFailures(), 0u);
}

TEST(AxisModelCounters, ConsecutiveFailuresAndTheTimeoutReport) {
  struct Step {
    const char* name;
    int event;  // 0 ok, 1 lost, 2 failed (wrong WKC), 3 ECatTErr observed
    std::uint32_t failed, lost;
    std::uint32_t unanswered;  // lost cycles awaiting ECatTErr
  };
  const Step steps[] = {
      {"lost", 1, 1, 1, 0},
      {"lost", 1, 2, 2, 0},
      {"ok after 2 lost", 0, 0, 0, 2},
      {"lost: a new outage", 1, 1, 1, 0},
      {"lost", 1, 2, 2, 0},
      {"lost", 1, 3, 3, 0},
      {"ok after 3 lost: awaiting ECatTErr", 0, 0, 0, 3},
      {"ECatTErr seen", 3, 0, 0, 0},
      {"wrong WKC", 2, 1, 0, 0},
      {"wrong WKC", 2, 2, 0, 0},
      {"wrong WKC", 2, 3, 0, 0},
      {"ok after 3 wrong WKCs: nothing to report", 0, 0, 0, 0},
  };
  AxisModel axis(0, std::nullopt);
  std::uint64_t frame = 0;
  for (const Step& step : steps) {
    SCOPED_TRACE(step.name);
    ++frame;
    switch (step.event) {
      case 0:
        axis.cycleOk(stamp(frame));
        break;
      case 1:
        axis.cycleFailed(true, 1, stamp(frame));
        break;
      case 2:
        axis.cycleFailed(false, 1, stamp(frame));
        break;
      default:
        axis.observe(pdo(kScwRunning, kSswRunning, kSummary | kEcatTErr), stamp(frame));
    }
    EXPECT_EQ(axis.consecutiveFailed(), step.failed);
    EXPECT_EQ(axis.consecutiveLost(), step.lost);
    EXPECT_EQ(axis.unansweredOutageCycles(), step.unanswered);
  }
  EXPECT_EQ(axis.totalFailures(), 8u);
}

TEST(AxisModelEnable, ValidEnableAndItsEnd) {
  AxisModel axis(0, std::nullopt);
  axis.observe(pdo(kScwOff, std::nullopt), stamp(1));
  EXPECT_FALSE(axis.validEnable());
  axis.observe(pdo(kScwArmed, std::nullopt), stamp(2));
  axis.observe(pdo(kScwRunning, std::nullopt), stamp(3));
  EXPECT_TRUE(axis.validEnable());
  EXPECT_FALSE(axis.illegalEnableEdge());
  axis.observe(pdo(kScwSe3, std::nullopt), stamp(4));
  EXPECT_FALSE(axis.validEnable());
  ASSERT_TRUE(axis.validEnableEnded().has_value());
  EXPECT_EQ(axis.validEnableEnded()->frame, 4u);
  axis.observe(pdo(kScwRunning, std::nullopt), stamp(5));
  EXPECT_TRUE(axis.illegalEnableEdge());
  EXPECT_EQ(axis.previousSe(), 3u);
  EXPECT_FALSE(axis.validEnable());

  AxisModel first(1, std::nullopt);
  first.observe(pdo(kScwRunning, std::nullopt), stamp(1));
  EXPECT_TRUE(first.validEnable()) << "first seen with SE 0x2";
  EXPECT_FALSE(first.illegalEnableEdge());
}

TEST(AxisModelSignals, FirstObservationHasNoEdges) {
  AxisModel axis(0, std::nullopt);
  axis.observe(pdo(kScwRunning | kZRequest | kClear, 0x1F), stamp(1));
  for (const Signal* s : {&axis.se(), &axis.zpulseRequest(), &axis.errorClear(), &axis.servoEn(),
                          &axis.servoRdy(), &axis.zpulseAck(), &axis.errClearAck()}) {
    EXPECT_TRUE(s->known);
    EXPECT_FALSE(s->rose);
    EXPECT_FALSE(s->fell);
    EXPECT_EQ(s->since.frame, 1u);
  }
  axis.observe(pdo(kScwRunning, 0x0F), stamp(2));
  EXPECT_TRUE(axis.zpulseRequest().fell);
  EXPECT_TRUE(axis.errorClear().fell);
  EXPECT_TRUE(axis.errClearAck().fell);
  EXPECT_FALSE(axis.servoEn().fell);
  EXPECT_EQ(axis.servoEn().since.frame, 1u);
  EXPECT_EQ(axis.errClearAck().since.frame, 2u);
}

// Signal::observe: edges only between two observations, and `since` where the value last changed.
struct SignalCase {
  const char* name;
  std::vector<std::uint32_t> values;  // one per frame, from frame 1
  bool rose, fell;
  std::uint64_t since;
};
const SignalCase kSignalCases[] = {
    {"first observation, 1", {1}, false, false, 1},
    {"first observation, 0", {0}, false, false, 1},
    {"0 -> 1 rises", {0, 1}, true, false, 2},
    {"1 -> 0 falls", {1, 0}, false, true, 2},
    {"unchanged keeps its since", {1, 1}, false, false, 1},
    {"one non-zero value to another is no edge", {1, 3}, false, false, 2},
    {"an edge lasts one observation", {0, 1, 1}, false, false, 2},
};

TEST(AxisModelSignals, EdgesAndSince) {
  for (const SignalCase& c : kSignalCases) {
    SCOPED_TRACE(c.name);
    Signal s;
    EXPECT_FALSE(s.on());
    EXPECT_FALSE(s.off());
    std::uint64_t frame = 0;
    for (std::uint32_t v : c.values) {
      s.clearEdges();
      s.observe(v, stamp(++frame));
    }
    EXPECT_EQ(s.rose, c.rose);
    EXPECT_EQ(s.fell, c.fell);
    EXPECT_EQ(s.since.frame, c.since);
    EXPECT_EQ(s.on(), c.values.back() != 0);
    EXPECT_EQ(s.off(), c.values.back() == 0);
  }
}

// docs/protocol.md §2: a valid enable is SE 0x1 -> 0x2 (or 0x2 when first seen), held since; any
// other way to 0x2 is the illegal edge of SE-001, for the frame it happens in.
struct EnableCase {
  const char* name;
  std::vector<std::uint32_t> se;  // SCW.SE per frame, from frame 1
  bool valid;
  bool illegal_edge;
  std::uint32_t previous_se;
  std::optional<std::uint64_t> ended;  // frame where the last valid enable ended
};
const EnableCase kEnableCases[] = {
    {"first seen enabled", {2}, true, false, 0, std::nullopt},
    {"armed, then enabled", {0, 1, 2}, true, false, 1, std::nullopt},
    {"held enabled", {1, 2, 2}, true, false, 2, std::nullopt},
    {"armed only", {0, 1}, false, false, 0, std::nullopt},
    {"off to enabled is illegal", {0, 2}, false, true, 0, std::nullopt},
    {"SE 0x3 to enabled is illegal", {3, 2}, false, true, 3, std::nullopt},
    {"the illegal edge lasts one frame", {0, 2, 2}, false, false, 2, std::nullopt},
    {"leaving 0x2 ends the enable", {1, 2, 0}, false, false, 2, 3},
    {"enabled again keeps the last end", {1, 2, 0, 1, 2}, true, false, 1, 3},
};

TEST(AxisModelEnable, SeSequences) {
  for (const EnableCase& c : kEnableCases) {
    SCOPED_TRACE(c.name);
    AxisModel axis(0, std::nullopt);
    std::uint64_t frame = 0;
    for (std::uint32_t se : c.se) axis.observe(pdo(kScwOff | se, std::nullopt), stamp(++frame));
    EXPECT_EQ(axis.validEnable(), c.valid);
    EXPECT_EQ(axis.illegalEnableEdge(), c.illegal_edge);
    EXPECT_EQ(axis.previousSe(), c.previous_se);
    ASSERT_EQ(axis.validEnableEnded().has_value(), c.ended.has_value());
    if (c.ended) {
      EXPECT_EQ(axis.validEnableEnded()->frame, *c.ended);
    }
  }
}

// Bounded memory: the timeline keeps its first kMaxTimeline changes and counts the rest.
TEST(AxisModelTimeline, KeepsAtMostMaxTimelineChanges) {
  AxisModel axis(0, std::nullopt);
  const std::size_t changes = AxisModel::kMaxTimeline + 10;
  for (std::size_t i = 0; i < changes; ++i) {
    const bool enabled = i % 2 == 1;
    axis.observe(pdo(enabled ? kScwRunning : kScwArmed, enabled ? kSswRunning : kSswReady),
                 stamp(i + 1));
  }
  EXPECT_EQ(axis.timeline().size(), AxisModel::kMaxTimeline);
  EXPECT_EQ(axis.timelineOmitted(), 10u);
  EXPECT_EQ(axis.state(), DriveState::ControlActive) << "the state follows past the bound";
  EXPECT_EQ(axis.timeline().back().at.frame, AxisModel::kMaxTimeline);
}

// The edges of an observation (the bit fields the model reads that changed, never on the first)
// and their texts, as the plugin shows them in ncservo.edge.
struct EdgeCase {
  const char* name;
  std::vector<std::pair<std::optional<std::uint32_t>, std::optional<std::uint32_t>>>
      steps;                            // SCW, SSW
  std::vector<std::string> last_edges;  // edgeText of the last observation's edges, in table order
};
const std::vector<EdgeCase>& edgeCases() {
  static const std::vector<EdgeCase> cases = {
      {"first observation: none", {{kScwRunning, kSswRunning}}, {}},
      {"SE armed then enabled", {{kScwArmed, kSswReady}, {kScwRunning, kSswReady}}, {"SE 0x1→0x2"}},
      {"ServoEn rises",
       {{kScwRunning, kSswReady}, {kScwRunning, kSswRunning}},
       {"ServoEn ↑", "PulseEnabled ↑"}},
      {"ServoEn falls",
       {{kScwRunning, kSswRunning}, {kScwRunning, kSswReady}},
       {"ServoEn ↓", "PulseEnabled ↓"}},
      {"outputs alone leave the inputs' bits",
       {{kScwRunning, kSswRunning}, {kScwOff, std::nullopt}},
       {"SE 0x2→0x0"}},
      {"unchanged: none", {{kScwRunning, kSswRunning}, {kScwRunning, kSswRunning}}, {}},
      {"ZPulseRequest rises",
       {{kScwRunning, kSswRunning}, {kScwRunning | kZRequest, kSswRunning}},
       {"ZPulseRequest ↑"}},
  };
  return cases;
}

TEST(AxisModelEdges, ChangedReadFieldsOfTheObservation) {
  for (const EdgeCase& c : edgeCases()) {
    SCOPED_TRACE(c.name);
    AxisModel axis(0, std::nullopt);
    std::uint64_t frame = 0;
    for (const auto& [scw, ssw] : c.steps) axis.observe(pdo(scw, ssw), stamp(++frame));
    std::vector<std::string> texts;
    for (const FieldEdge& edge : axis.edgesIn(frame)) texts.push_back(edgeText(edge));
    EXPECT_EQ(texts, c.last_edges);
    EXPECT_TRUE(axis.edgesIn(frame + 1).empty());  // no observation taken there
  }
}

// ncservo.transition: the name (docs/protocol.md §6) where the change has one, else the two states.
struct TransitionTextCase {
  const char* name;
  StateChange change;
  const char* text;
};
TEST(AxisModelTimeline, TransitionTexts) {
  const TransitionTextCase cases[] = {
      {"named",
       {DriveState::ControlActive, "ENABLE OPERATION", {}, DriveState::ReadyToSwitchOn},
       "ENABLE OPERATION"},
      {"unnamed",
       {DriveState::SwitchedOn, nullptr, {}, DriveState::ReadyToSwitchOn},
       "ready to switch on → switched on"},
      {"first known",
       {DriveState::ReadyToSwitchOn, nullptr, {}, std::nullopt},
       "→ ready to switch on"},
  };
  for (const TransitionTextCase& c : cases) {
    SCOPED_TRACE(c.name);
    EXPECT_EQ(transitionText(c.change), c.text);
  }
}

TEST(AxisModelTimeline, StateChangeInItsFrameOnly) {
  AxisModel axis(0, std::nullopt);
  axis.observe(pdo(kScwRunning, kSswReady), stamp(1));
  axis.observe(pdo(kScwRunning, kSswRunning), stamp(2));
  axis.observe(pdo(kScwRunning, kSswRunning), stamp(3));
  ASSERT_NE(axis.stateChangeIn(2), nullptr);
  EXPECT_EQ(axis.stateChangeIn(2)->from, axis.timeline().front().state);
  EXPECT_EQ(axis.stateChangeIn(2)->state, axis.timeline().back().state);
  EXPECT_EQ(axis.stateChangeIn(3), nullptr);
}

}  // namespace
}  // namespace ncservo
