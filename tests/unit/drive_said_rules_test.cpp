// The rules on what the drives and the ESCs say themselves (docs/rules.md MBX-003, ERH-001,
// LNK-001, LNK-002, DC-001): each row an event the slave trackers give, and whether and how
// the rule judges it; then DC-001's runs on 0x092C reads built byte by byte.
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/model/dc_clock.hpp"
#include "ncservo/rules/rules.hpp"
#include "ncservo/wire/slave_directory.hpp"
#include "row_name.hpp"

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

}  // namespace
}  // namespace ncservo
