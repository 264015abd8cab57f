// The rules on what the drives and the ESCs say themselves (docs/rules.md MBX-003, ERH-001,
// LNK-001, LNK-002, DC-001): each row an event the slave trackers give, and whether and how
// the rule judges it; then DC-001's runs on 0x092C reads built byte by byte; then the rules on a
// drive's own words against its SEW (MBX-001, MBX-002, ERH-002), each row a script of cycles
// and mailbox reads through the validator.
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/model/dc_clock.hpp"
#include "ncservo/rules/rules.hpp"
#include "ncservo/wire/slave_directory.hpp"
#include "row_name.hpp"
#include "timeline_run.hpp"

namespace ncservo {
namespace {

SlaveRef station(std::uint16_t address) {
  return SlaveRef{address, std::nullopt};
}

LinkFault linkInto(std::uint16_t downstream, std::uint16_t upstream, std::uint32_t errors) {
  LinkFault link;
  link.upstream = station(upstream);
  link.upstream_port = 1;
  link.downstream = station(downstream);
  link.downstream_port = 0;
  link.reported = station(downstream);
  link.reported_port = 0;
  link.errors = errors;
  return link;
}

struct JudgeRow {
  const char* name;
  BusEventData event;
  std::optional<RuleId> fires;  // none: no rule fires
  const char* says = "";        // a part of its message
};

std::vector<JudgeRow> judgeRows() {
  SdoAbortEvent missing{station(0x1001), 0x2000, 0, 0x06020000, 17, false};
  SdoAbortEvent empty_history{station(0x1001), 0x1003, 1, 0x08000024, 40, true};
  SdoAbortEvent unknown_code{station(0x1001), 0x6060, 0, 0x12345678, std::nullopt, false};
  LinkErrorEvent rx{linkInto(0x03EB, 0x03EA, 3), false, 120};
  LinkErrorEvent rx_unplaced{LinkFault{}, false, 0};
  rx_unplaced.link.reported = station(0x03EC);
  rx_unplaced.link.downstream = station(0x03EC);
  rx_unplaced.link.reported_port = 2;
  rx_unplaced.link.errors = 1;
  LinkErrorEvent lost{linkInto(0x03EB, 0x03EA, 2), true, 120};
  return {
      {"AbortOfAMissingObject", missing, RuleId::Mbx003,
       "station 0x1001: SDO 2000h:00 aborted with 0x06020000 (object does not exist), the "
       "request in frame 17"},
      {"AbortOfAnEmptyHistoryEntryIsExpected", empty_history, std::nullopt},
      {"AbortWithACodeNoTableKnows", unknown_code, RuleId::Mbx003,
       "0x12345678 (a code CiA 301 does not list)"},
      {"HistoryShrunk", ErrorHistoryShrunkEvent{station(0x1002), 3, 1, 55}, RuleId::Erh001,
       "station 0x1002: error history 1003h:00 read 1, 3 in frame 55"},
      {"RxErrorsNotForwarded", rx, RuleId::Lnk001,
       "station 0x03EB: 3 RX or invalid-frame errors at port 0 since the read in frame 120, none "
       "forwarded from upstream: the link between station 0x03EA port 1 and station 0x03EB port "
       "0"},
      {"RxErrorsAfterAClearAtAPortWithNoKnownNeighbour", rx_unplaced, RuleId::Lnk001,
       "1 RX or invalid-frame error at port 2 since they were cleared, none forwarded from "
       "upstream: the link into station 0x03EC port 2"},
      {"LinkLost", lost, RuleId::Lnk002,
       "station 0x03EB: the link at port 0 went down 2 times since the read in frame 120: the "
       "link between station 0x03EA port 1 and station 0x03EB port 0"},
      {"WithinTheLimit", DcDifferenceEvent{station(0x1001), -1000, 50, 10, 50}, std::nullopt},
      {"FirstReadBeyondTheLimitIsConvergence",
       DcDifferenceEvent{station(0x1001), 1001, std::nullopt, 0, std::nullopt}, std::nullopt},
      {"NeverWithinTheLimitIsConvergence", DcDifferenceEvent{station(0x1001), 900, 4000, 9, 4000},
       std::nullopt},
      {"BeyondTheLimitOnceSynchronised", DcDifferenceEvent{station(0x1001), 1001, 20, 10, 1000},
       RuleId::Dc001,
       "station 0x1001: system time difference (0x092C) +1001 ns, beyond dc_sync_limit_ns = 1000 "
       "(the read before, frame 10: +20 ns)"},
      {"NegativeBeyondTheLimit", DcDifferenceEvent{station(0x1001), -5000, 20, 10, 20},
       RuleId::Dc001, "-5000 ns, beyond dc_sync_limit_ns = 1000"},
      {"StillBeyondTheLimit", DcDifferenceEvent{station(0x1001), 7000, -5000, 11, 20},
       std::nullopt},
  };
}

class DriveSaidRules : public ::testing::TestWithParam<JudgeRow> {};

TEST_P(DriveSaidRules, Judged) {
  const JudgeRow& row = GetParam();
  const BusEvent event{Stamp{200, 0}, row.event};
  std::vector<EventFinding> found;
  MeasurementRuns runs;
  judgeEvent(event, RuleSettings{}, runs, found);
  if (!row.fires) {
    EXPECT_TRUE(found.empty()) << found.front().message;
    return;
  }
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].rule, *row.fires);
  EXPECT_NE(found[0].message.find(row.says), std::string::npos) << found[0].message;
  EXPECT_TRUE(found[0].slave.station) << "a slave rule's finding names its slave";
}

INSTANTIATE_TEST_SUITE_P(Rules, DriveSaidRules, ::testing::ValuesIn(judgeRows()),
                         test::rowName<JudgeRow>);

TEST(DriveSaidRules, DisabledOrLimitRaised) {
  const BusEvent dc{Stamp{5, 0}, DcDifferenceEvent{station(0x1001), 5000, 10, 4, 10}};
  RuleSettings settings;
  ASSERT_TRUE(settings.setLimit("dc_sync_limit_ns", 5000));
  std::vector<EventFinding> found;
  MeasurementRuns runs;
  judgeEvent(dc, settings, runs, found);
  EXPECT_TRUE(found.empty()) << "5000 ns is within a limit of 5000";
  ASSERT_TRUE(settings.setLimit("dc_sync_limit_ns", 4999));
  judgeEvent(dc, settings, runs, found);
  EXPECT_EQ(found.size(), 1u);
  found.clear();
  const BusEvent abort{Stamp{5, 0}, SdoAbortEvent{station(1), 0x2000, 0, 0x06020000, {}, false}};
  ASSERT_TRUE(settings.disable("MBX-003"));
  judgeEvent(abort, settings, runs, found);
  EXPECT_TRUE(found.empty());
}

// DC-001 on the reads as DcClock gives them: the converging reads before the first within the
// limit are not judged; then a run of reads beyond the limit is one finding, on its first read,
// and a read within the limit ends the run.
TEST(DcOutOfSync, OneFindingPerRunOnItsFirstRead) {
  DcClock clock(100);
  FrameAddressing addressing;
  std::vector<std::uint64_t> fired;
  std::uint64_t frame = 0;
  // 0x092C: bit 31 the sign (1: the local copy is behind), bits 30..0 the magnitude.
  for (std::uint32_t raw : {80000u, 0x80000000u | 9000u, 500u, 5000u, 6000u, 0x80000000u | 200u,
                            0x80000000u | 3000u, 900u}) {
    test::Bytes data;
    test::putLe(data, raw, 4);
    test::FrameBuilder builder;
    builder.add(test::Dg{ecat::kFprd, 0, test::physical(0x1001, ecat::kRegDcSystemTimeDifference),
                         data, 1});
    const test::Bytes bytes = builder.bytes();
    const test::Walked w = test::walk(bytes);
    addressing.beginFrame(*w.frame, true, false);
    std::vector<BusEvent> events;
    ++frame;
    clock.onFrame(*w.frame, w.reader(), addressing, Stamp{frame, 0}, 0, events);
    ASSERT_EQ(events.size(), 1u) << "frame " << frame;
    std::vector<EventFinding> found;
    MeasurementRuns runs;
    judgeEvent(events[0], RuleSettings{}, runs, found);
    for (const EventFinding& f : found) {
      EXPECT_EQ(f.rule, RuleId::Dc001);
      EXPECT_EQ(f.slave.station, 0x1001);
      fired.push_back(frame);
    }
  }
  EXPECT_EQ(fired, (std::vector<std::uint64_t>{4, 7}));
}

// --- A drive's own words against its SEW (docs/drive-messages.md#the-rules) ---

using test::kEncoderErr;
using test::kEnd;
using test::kSummary;
using test::M;
using test::R;
using test::Script;
constexpr std::uint32_t kFault = kSummary | kEncoderErr;  // E01 EncoderErr: 0x7305 (§7)

struct WordsRow {
  const char* name;
  Script script;
  // The findings of MBX-001, MBX-002 and ERH-002, in order: rule, frame, since.
  std::vector<std::tuple<RuleId, test::At, test::At>> expected;
  const char* says = "";  // a part of the first one's message
};

std::vector<WordsRow> wordsRows() {
  const Script drive = Script(80).stations(0x1001);
  // A drive that reported a fault with an emergency (cycle 3), cleared at 6.
  const Script reporting = Script(drive).emergency(3, 0x7305).sew(3, 6, kFault);
  return {
      // MBX-001: drive_response (20 ms) after the emergency, on the first frame past it.
      {"EmergencyWithNoFault",
       Script(drive).emergency(10, 0x8611),
       {{RuleId::Mbx001, M(31), R(10)}},
       "the drive sent emergency 0x8611 (following error too large), but no SEW cause bit rose "
       "within 20 ms before or after it"},
      {"EmergencyAnsweredAfter", Script(drive).emergency(10, 0x7305).sew(25, kEnd, kFault), {}},
      {"EmergencyAnsweredBefore", Script(drive).sew(10, kEnd, kFault).emergency(25, 0x7305), {}},
      {"EmergencyInTheFaultsFrame", Script(drive).sew(10, kEnd, kFault).emergency(10, 0x7305), {}},
      {"ErrorResetIsNoFault", Script(drive).emergency(10, 0x0000), {}},
      {"FaultLongerBefore",
       Script(drive).sew(5, kEnd, kFault).emergency(30, 0x7305),
       {{RuleId::Mbx001, M(51), R(30)}},
       "; the last rose 25.000 ms before it (frame 12)"},
      // Neither answers the other: each is a finding.
      {"AnswerTooLate",
       Script(drive).emergency(10, 0x7305).sew(35, kEnd, kFault),
       {{RuleId::Mbx001, M(31), R(10)}, {RuleId::Mbx002, M(56), R(35)}}},
      {"TwoEmergenciesTwoFindings",
       Script(drive).emergency(10, 0x8611).emergency(40, 0x8611),
       {{RuleId::Mbx001, M(31), R(10)}, {RuleId::Mbx001, M(61), R(40)}}},
      {"WindowOpenAtTheEnd", Script(drive).emergency(70, 0x8611), {}},
      // MBX-002: a drive that sent an emergency before faults again without one.
      {"FaultWithoutEmergency",
       Script(reporting).sew(30, kEnd, kFault),
       {{RuleId::Mbx002, M(51), R(30)}},
       "SEW E01 EncoderErr (0x7305) rose, but the drive, which sent an emergency in frame 8, "
       "sent none within 20 ms before or after it"},
      {"FaultAnsweredAfter", Script(reporting).sew(30, kEnd, kFault).emergency(45, 0x7305), {}},
      {"FaultAnsweredBefore", Script(reporting).emergency(20, 0x7305).sew(30, kEnd, kFault), {}},
      {"NoEmergencyEverSent", Script(drive).sew(30, kEnd, kFault), {}},
      {"ResetCountsAsSent",
       Script(drive).sew(3, 6, kFault).emergency(8, 0x0000).sew(30, kEnd, kFault),
       {{RuleId::Mbx002, M(51), R(30)}}},
      // ERH-002: the newest entry read after a fault, judged on the read.
      {"HistoryDisagrees",
       Script(drive).sew(10, kEnd, kFault).historyRead(15, 0x0D218611),
       {{RuleId::Erh002, R(15), R(15)}},
       "1003h:01 read 0x0D218611, code 0x8611 (following error too large), after the fault in "
       "frame 22 raised SEW E01 EncoderErr (0x7305)"},
      {"HistoryAgrees", Script(drive).sew(10, kEnd, kFault).historyRead(15, 0x07017305), {}},
      {"ReadBeforeAnyFault", Script(drive).historyRead(5, 0x0D218611).sew(10, kEnd, kFault), {}},
      {"OnlyTheFirstReadAfterAFault",
       Script(drive).sew(10, kEnd, kFault).historyRead(15, 0x0D218611).historyRead(20, 0x07017305),
       {{RuleId::Erh002, R(15), R(15)}}},
      {"EachFaultItsRead",
       Script(drive)
           .sew(10, 20, kFault)
           .historyRead(15, 0x0D218611)
           .sew(30, kEnd, kFault)
           .historyRead(35, 0x0D218611),
       {{RuleId::Erh002, R(15), R(15)}, {RuleId::Erh002, R(35), R(35)}}},
  };
}

class DriveWordsRules : public ::testing::TestWithParam<WordsRow> {};

TEST_P(DriveWordsRules, Judged) {
  const WordsRow& row = GetParam();
  const test::Recorded r = test::record(row.script);
  std::vector<const Finding*> found;
  for (const Finding& f : r.findings) {
    if (f.rule == RuleId::Mbx001 || f.rule == RuleId::Mbx002 || f.rule == RuleId::Erh002) {
      found.push_back(&f);
    }
  }
  ASSERT_EQ(found.size(), row.expected.size()) << (found.empty() ? "" : found[0]->message);
  for (std::size_t i = 0; i < found.size(); ++i) {
    const auto& [rule, at, since] = row.expected[i];
    EXPECT_EQ(found[i]->rule, rule) << i;
    EXPECT_EQ(found[i]->axis, 0) << i;
    EXPECT_EQ(found[i]->at.frame, test::recordedFrame(at)) << i << ": " << found[i]->message;
    EXPECT_EQ(found[i]->since.frame, test::recordedFrame(since)) << i;
  }
  if (!found.empty()) {
    EXPECT_NE(found[0]->message.find(row.says), std::string::npos) << found[0]->message;
  }
  // The rows declare what they read (sew, mailbox): the fast path changes nothing.
  const test::Recorded slow = test::record(row.script, nullptr, FastPath::Off);
  ASSERT_EQ(slow.findings.size(), r.findings.size());
  for (std::size_t i = 0; i < r.findings.size(); ++i) {
    EXPECT_EQ(slow.findings[i].rule, r.findings[i].rule) << i;
    EXPECT_EQ(slow.findings[i].at.frame, r.findings[i].at.frame) << i;
    EXPECT_EQ(slow.findings[i].message, r.findings[i].message) << i;
  }
}

INSTANTIATE_TEST_SUITE_P(Rows, DriveWordsRules, ::testing::ValuesIn(wordsRows()),
                         test::rowName<WordsRow>);

TEST(DriveWordsRules, DisabledNotJudged) {
  RuleSettings settings;
  ASSERT_TRUE(settings.disable("MBX-001"));
  const test::Recorded r =
      test::record(Script(80).stations(0x1001).emergency(10, 0x8611).settings(settings));
  for (const Finding& f : r.findings) EXPECT_NE(f.rule, RuleId::Mbx001) << f.message;
}

TEST(DriveWordsRules, AnEmergencyIsAnsweredAroundIt) {
  const std::optional<AllowedWindow> w = allowedWindow(ruleDef(RuleId::Mbx001), RuleSettings{});
  ASSERT_TRUE(w.has_value());
  EXPECT_EQ(w->from_ns, -20 * test::kMs);
  EXPECT_EQ(w->to_ns, 20 * test::kMs);
}

}  // namespace
}  // namespace ncservo
