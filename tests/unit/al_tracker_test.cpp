// Each slave's EtherCAT state machine (al_tracker.hpp, docs/protocol.md §8; ESM-001, ESM-003 and
// ESM-004 of docs/rules.md), on frames built byte by byte and walked over exact-size heap buffers.
#include "ncservo/model/al_tracker.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/rules/rules.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::Dg;
using test::FrameBuilder;
using test::physical;

constexpr std::uint8_t kInit = 1;
constexpr std::uint8_t kPreOp = 2;
constexpr std::uint8_t kBoot = 3;
constexpr std::uint8_t kSafeOp = 4;
constexpr std::uint8_t kOp = 8;

constexpr std::uint16_t kRegStation = 0x0010;
constexpr std::uint16_t kRegControl = 0x0120;
constexpr std::uint16_t kRegStatus = 0x0130;
constexpr std::uint16_t kStation0 = 0x1001;
constexpr std::uint16_t kStation1 = 0x1002;

Bytes le16(std::uint16_t value) {
  Bytes out;
  test::putLe(out, value, 2);
  return out;
}
// ADP of the slave at a ring position (auto-increment addressing puts -position in ADP).
std::uint16_t apAdp(std::uint16_t position) {
  return static_cast<std::uint16_t>((0x10000u - position) & 0xFFFFu);
}

Bytes frameOf(const std::vector<Dg>& dgs) {
  FrameBuilder builder;
  for (const Dg& dg : dgs) builder.add(dg);
  return builder.bytes();
}

// The tracker's events as the slave rules judge them (rules.hpp judgeEvent).
struct AlFinding {
  RuleId rule{};
  std::optional<std::uint16_t> station;
  std::optional<std::uint16_t> position;
  std::string message;
};

// Feeds frames to one tracker, numbering them from 1, and keeps every finding.
struct Harness {
  AlTracker tracker;
  std::uint64_t frame = 0;
  std::vector<AlFinding> findings;

  std::vector<AlFinding> feedBytes(const Bytes& bytes, std::size_t size, bool returned,
                                   bool paired) {
    const test::Walked w = test::walk(bytes, size);
    std::vector<BusEvent> events;
    ++frame;
    tracker.onFrame(*w.frame, w.reader(), returned, paired, Stamp{frame, 0}, events);
    std::vector<EventFinding> judged;
    MeasurementRuns runs;
    for (const BusEvent& event : events) judgeEvent(event, RuleSettings{}, runs, judged);
    std::vector<AlFinding> out;
    for (EventFinding& f : judged) {
      out.push_back({f.rule, f.slave.station, f.slave.position, std::move(f.message)});
    }
    findings.insert(findings.end(), out.begin(), out.end());
    return out;
  }
  std::vector<AlFinding> feed(const std::vector<Dg>& dgs, bool returned, bool paired) {
    const Bytes bytes = frameOf(dgs);
    return feedBytes(bytes, bytes.size(), returned, paired);
  }
  // A master's copy (its data as sent, WKC 0) followed by its returned copy.
  std::vector<AlFinding> exchange(const std::vector<Dg>& master, const std::vector<Dg>& back) {
    std::vector<AlFinding> out = feed(master, false, false);
    std::vector<AlFinding> more = feed(back, true, true);
    out.insert(out.end(), more.begin(), more.end());
    return out;
  }

  // Start-up writes of station addresses: kStation0 + k to ring position k.
  void assignStations(std::uint16_t slaves) {
    std::vector<Dg> master;
    std::vector<Dg> back;
    for (std::uint16_t k = 0; k < slaves; ++k) {
      const Bytes station = le16(static_cast<std::uint16_t>(kStation0 + k));
      const auto index = static_cast<std::uint8_t>(k);
      master.push_back(Dg{ecat::kApwr, index, physical(apAdp(k), kRegStation), station, 0});
      back.push_back(Dg{ecat::kApwr, index,
                        physical(static_cast<std::uint16_t>(apAdp(k) + slaves), kRegStation),
                        station, 1});
    }
    exchange(master, back);
  }
  // FPWR of AL control.
  std::vector<AlFinding> request(std::uint16_t station, std::uint16_t control) {
    const Dg dg{ecat::kFpwr, 0, physical(station, kRegControl), le16(control), 0};
    Dg back = dg;
    back.wkc = 1;
    return exchange({dg}, {back});
  }
  // FPRD of AL status; with a status code, a 6-byte read that covers 0x0134 too.
  std::vector<AlFinding> status(std::uint16_t station, std::uint16_t value,
                                std::optional<std::uint16_t> code = std::nullopt,
                                std::uint16_t wkc = 1) {
    Bytes data = le16(value);
    if (code) {
      test::putLe(data, 0, 2);
      test::putLe(data, *code, 2);
    }
    const Dg dg{ecat::kFprd, 0, physical(station, kRegStatus), Bytes(data.size(), 0), 0};
    const Dg back{ecat::kFprd, 0, physical(station, kRegStatus), data, wkc};
    return exchange({dg}, {back});
  }

  std::size_t count(RuleId rule) const {
    std::size_t n = 0;
    for (const AlFinding& f : findings) n += f.rule == rule ? 1 : 0;
    return n;
  }
  bool anyEsm() const {  // ESM-004 is information, not an "ESM finding"
    return count(RuleId::Esm001) + count(RuleId::Esm002) + count(RuleId::Esm003) > 0;
  }
};

std::string describe(const std::vector<AlFinding>& findings) {
  std::string out;
  for (const AlFinding& f : findings) out += f.message + "\n";
  return out;
}

// --- the transition table -------------------------------------------------------------------

struct TransitionCase {
  std::uint8_t from;
  std::uint8_t to;
  bool allowed;
};
class AlTrackerTransition : public ::testing::TestWithParam<TransitionCase> {};

TEST_P(AlTrackerTransition, MatchesProtocol) {
  const TransitionCase& c = GetParam();
  EXPECT_EQ(alTransitionAllowed(c.from, c.to), c.allowed)
      << alStateName(c.from) << " -> " << alStateName(c.to);
}

INSTANTIATE_TEST_SUITE_P(
    AlTracker, AlTrackerTransition,
    ::testing::Values(
        // from INIT
        TransitionCase{kInit, kInit, true}, TransitionCase{kInit, kPreOp, true},
        TransitionCase{kInit, kBoot, true}, TransitionCase{kInit, kSafeOp, false},
        TransitionCase{kInit, kOp, false},
        // from PRE-OP
        TransitionCase{kPreOp, kInit, true}, TransitionCase{kPreOp, kPreOp, true},
        TransitionCase{kPreOp, kBoot, false}, TransitionCase{kPreOp, kSafeOp, true},
        TransitionCase{kPreOp, kOp, false},
        // from BOOT
        TransitionCase{kBoot, kInit, true}, TransitionCase{kBoot, kPreOp, false},
        TransitionCase{kBoot, kBoot, true}, TransitionCase{kBoot, kSafeOp, false},
        TransitionCase{kBoot, kOp, false},
        // from SAFE-OP
        TransitionCase{kSafeOp, kInit, true}, TransitionCase{kSafeOp, kPreOp, true},
        TransitionCase{kSafeOp, kBoot, false}, TransitionCase{kSafeOp, kSafeOp, true},
        TransitionCase{kSafeOp, kOp, true},
        // from OP
        TransitionCase{kOp, kInit, true}, TransitionCase{kOp, kPreOp, true},
        TransitionCase{kOp, kBoot, false}, TransitionCase{kOp, kSafeOp, true},
        TransitionCase{kOp, kOp, true},
        // requests that are not states, and non-states as the current state
        TransitionCase{kInit, 0, false}, TransitionCase{kPreOp, 5, false},
        TransitionCase{kOp, 0x0F, false}, TransitionCase{0, kInit, false},
        TransitionCase{6, kPreOp, false}, TransitionCase{0, 0, false},
        TransitionCase{5, 5, false}));

struct NameCase {
  std::uint8_t state;
  const char* name;
};
class AlTrackerStateName : public ::testing::TestWithParam<NameCase> {};
TEST_P(AlTrackerStateName, Names) {
  EXPECT_STREQ(alStateName(GetParam().state), GetParam().name);
}
INSTANTIATE_TEST_SUITE_P(AlTracker, AlTrackerStateName,
                         ::testing::Values(NameCase{1, "INIT"}, NameCase{2, "PRE-OP"},
                                           NameCase{3, "BOOT"}, NameCase{4, "SAFE-OP"},
                                           NameCase{8, "OP"}, NameCase{0, "0x0"},
                                           NameCase{5, "0x5"}, NameCase{0x0F, "0xF"},
                                           NameCase{0x10, "?"}));

// --- a legal start-up --------------------------------------------------------------------------

TEST(AlTracker, LegalStartUpRaisesNothingAndEntersOp) {
  Harness h;
  // Reset of every slave to INIT with error acknowledge before anything is known.
  h.exchange({Dg{ecat::kBwr, 0, physical(0, kRegControl), le16(0x0011), 0}},
             {Dg{ecat::kBwr, 0, physical(2, kRegControl), le16(0x0011), 2}});
  h.assignStations(2);
  for (std::uint16_t station : {kStation0, kStation1}) {
    EXPECT_EQ(h.tracker.stateOfStation(station), std::nullopt);
    h.status(station, kInit);
    EXPECT_EQ(h.tracker.stateOfStation(station), kInit);
  }
  for (std::uint8_t next : {kPreOp, kSafeOp, kOp}) {
    for (std::uint16_t station : {kStation0, kStation1}) {
      h.request(station, next);
      h.status(station, next);
      EXPECT_EQ(h.tracker.stateOfStation(station), next);
      EXPECT_EQ(h.tracker.opEntries(station), next == kOp ? 1u : 0u) << alStateName(next);
    }
  }
  // Still OP on the next read: not entered again.
  h.status(kStation0, kOp);
  EXPECT_EQ(h.tracker.opEntries(kStation0), 1u);
  EXPECT_TRUE(h.findings.empty()) << describe(h.findings);
}

// --- ESM-001 ----------------------------------------------------------------------------------

enum class Via { Fpwr, ApwrAfterAssign, ApwrAssignAfterRead, Bwr };
struct RequestCase {
  const char* name;
  std::optional<std::uint8_t> known;  // AL status read before the request; none: never read
  std::uint16_t control;              // AL control written
  Via via;
  std::size_t esm001;   // findings expected
  const char* message;  // expected in the finding's message
};
class AlTrackerRequest : public ::testing::TestWithParam<RequestCase> {};

TEST_P(AlTrackerRequest, Esm001) {
  const RequestCase& c = GetParam();
  Harness h;
  if (c.via != Via::ApwrAssignAfterRead) h.assignStations(1);
  if (c.known) h.status(kStation0, *c.known);
  if (c.via == Via::ApwrAssignAfterRead) h.assignStations(1);  // merges the station's record
  std::vector<AlFinding> out;
  switch (c.via) {
    case Via::Fpwr:
      out = h.request(kStation0, c.control);
      break;
    case Via::ApwrAfterAssign:
    case Via::ApwrAssignAfterRead:
      out = h.exchange({Dg{ecat::kApwr, 0, physical(apAdp(0), kRegControl), le16(c.control), 0}},
                       {Dg{ecat::kApwr, 0, physical(1, kRegControl), le16(c.control), 1}});
      break;
    case Via::Bwr:
      out = h.exchange({Dg{ecat::kBwr, 0, physical(0, kRegControl), le16(c.control), 0}},
                       {Dg{ecat::kBwr, 0, physical(1, kRegControl), le16(c.control), 1}});
      break;
  }
  ASSERT_EQ(out.size(), c.esm001) << describe(out);
  EXPECT_EQ(h.findings.size(), c.esm001) << describe(h.findings);
  for (const AlFinding& f : out) {
    EXPECT_EQ(f.rule, RuleId::Esm001);
    EXPECT_EQ(f.station, kStation0);
    EXPECT_EQ(f.position, 0);
    EXPECT_NE(f.message.find(c.message), std::string::npos) << f.message;
    EXPECT_NE(f.message.find("station 0x1001 (ring position 0)"), std::string::npos) << f.message;
  }
}

INSTANTIATE_TEST_SUITE_P(
    AlTracker, AlTrackerRequest,
    ::testing::Values(
        RequestCase{"InitToOp", kInit, 0x0008, Via::Fpwr, 1,
                    "requests OP from known state INIT; allowed: INIT, PRE-OP, BOOT"},
        RequestCase{"SafeOpToBoot", kSafeOp, 0x0003, Via::Fpwr, 1,
                    "requests BOOT from known state SAFE-OP; allowed: INIT, PRE-OP, SAFE-OP, OP"},
        RequestCase{"InitToNonState", kInit, 0x0005, Via::Fpwr, 1,
                    "requests 0x5 from known state INIT"},
        RequestCase{"InitToPreOp", kInit, 0x0002, Via::Fpwr, 0, ""},
        RequestCase{"AckKeepsState", kSafeOp, 0x0014, Via::Fpwr, 0, ""},
        RequestCase{"OpToInit", kOp, 0x0001, Via::Fpwr, 0, ""},
        RequestCase{"UnknownStateToOp", std::nullopt, 0x0008, Via::Fpwr, 0, ""},
        RequestCase{"UnknownStateToNonState", std::nullopt, 0x0007, Via::Fpwr, 0, ""},
        RequestCase{"ByPositionAfterAssign", kPreOp, 0x0008, Via::ApwrAfterAssign, 1,
                    "AL control 0x0008 requests OP from known state PRE-OP"},
        RequestCase{"ByPositionAssignedLater", kInit, 0x0004, Via::ApwrAssignAfterRead, 1,
                    "requests SAFE-OP from known state INIT"},
        RequestCase{"Broadcast", kInit, 0x0018, Via::Bwr, 1,
                    "AL control 0x0018 requests OP from known state INIT"},
        RequestCase{"BroadcastLegal", kOp, 0x0001, Via::Bwr, 0, ""}),
    [](const ::testing::TestParamInfo<RequestCase>& row) { return row.param.name; });

TEST(AlTracker, BroadcastRequestReportsEachSlaveItForbids) {
  Harness h;
  h.assignStations(3);
  h.status(kStation0, kInit);
  h.status(kStation1, kSafeOp);  // the third slave's state is not known
  const auto out = h.exchange({Dg{ecat::kBwr, 0, physical(0, kRegControl), le16(0x0004), 0}},
                              {Dg{ecat::kBwr, 0, physical(3, kRegControl), le16(0x0004), 3}});
  ASSERT_EQ(out.size(), 1u) << describe(out);
  EXPECT_EQ(out[0].station, kStation0);

  const auto to_op =
      h.feed({Dg{ecat::kBwr, 0, physical(0, kRegControl), le16(0x0008), 0}}, false, false);
  ASSERT_EQ(to_op.size(), 1u) << describe(to_op);  // only the slave known to be in INIT
  EXPECT_EQ(to_op[0].station, kStation0);
}

TEST(AlTracker, WritesOfAPairedReturnedCopyAreNotJudgedTwice) {
  Harness h;
  h.assignStations(1);
  h.status(kStation0, kInit);
  const auto out = h.request(kStation0, kOp);  // master copy and its returned copy
  EXPECT_EQ(out.size(), 1u) << describe(out);
  // A returned copy whose master copy was not captured carries the write too.
  const auto unpaired =
      h.feed({Dg{ecat::kFpwr, 0, physical(kStation0, kRegControl), le16(kOp), 1}}, true, false);
  EXPECT_EQ(unpaired.size(), 1u) << describe(unpaired);
}

// --- ESM-003 / ESM-004 --------------------------------------------------------------------------

enum class Code { None, SameFrame, LaterDatagram, Earlier };
struct ErrorCase {
  const char* name;
  std::optional<std::uint8_t> previous;  // known state before
  std::optional<std::uint16_t> request;  // AL control written after that read
  std::uint16_t status;                  // AL status read with the error indicator
  Code code;
  RuleId rule;
  const char* message;
};
class AlTrackerError : public ::testing::TestWithParam<ErrorCase> {};

TEST_P(AlTrackerError, Reported) {
  const ErrorCase& c = GetParam();
  Harness h;
  if (c.previous) h.status(kStation0, *c.previous);
  if (c.code == Code::Earlier) {
    const Dg dg{ecat::kFprd, 0, physical(kStation0, 0x0134), Bytes(2, 0), 0};
    const Dg back{ecat::kFprd, 0, physical(kStation0, 0x0134), le16(0x0024), 1};
    h.exchange({dg}, {back});
  }
  if (c.request) h.request(kStation0, *c.request);
  std::vector<AlFinding> out;
  switch (c.code) {
    case Code::None:
    case Code::Earlier:
      out = h.status(kStation0, c.status);
      break;
    case Code::SameFrame:
      out = h.status(kStation0, c.status, 0x001D);
      break;
    case Code::LaterDatagram: {
      const std::vector<Dg> master{
          Dg{ecat::kFprd, 0, physical(kStation0, kRegStatus), Bytes(2, 0), 0},
          Dg{ecat::kFprd, 1, physical(kStation0, 0x0134), Bytes(2, 0), 0}};
      const std::vector<Dg> back{
          Dg{ecat::kFprd, 0, physical(kStation0, kRegStatus), le16(c.status), 1},
          Dg{ecat::kFprd, 1, physical(kStation0, 0x0134), le16(0x0011), 1}};
      out = h.exchange(master, back);
      break;
    }
  }
  ASSERT_EQ(out.size(), 1u) << describe(h.findings);
  EXPECT_EQ(h.findings.size(), 1u) << describe(h.findings);
  EXPECT_EQ(out[0].rule, c.rule) << out[0].message;
  EXPECT_EQ(out[0].station, kStation0);
  EXPECT_NE(out[0].message.find(c.message), std::string::npos) << out[0].message;
}

INSTANTIATE_TEST_SUITE_P(
    AlTracker, AlTrackerError,
    ::testing::Values(
        ErrorCase{"PreOpRequestedWithCode", kInit, kPreOp, 0x0012, Code::SameFrame, RuleId::Esm003,
                  "station 0x1001: AL status 0x0012 (PRE-OP + error) while PRE-OP requested; "
                  "AL status code 0x001D (invalid output configuration)"},
        ErrorCase{"SafeOpRefused", kPreOp, kSafeOp, 0x0012, Code::None, RuleId::Esm003,
                  "AL status 0x0012 (PRE-OP + error) while SAFE-OP requested; AL status code "
                  "not read"},
        ErrorCase{
            "CodeInLaterDatagram", kPreOp, kSafeOp, 0x0012, Code::LaterDatagram, RuleId::Esm003,
            "while SAFE-OP requested; AL status code 0x0011 (invalid requested state change)"},
        ErrorCase{"CodeReadEarlier", kSafeOp, kOp, 0x0014, Code::Earlier, RuleId::Esm003,
                  "AL status code 0x0024 (invalid input mapping, read in frame 4)"},
        ErrorCase{"InitRequested", kPreOp, 0x0011, 0x0011, Code::None, RuleId::Esm004,
                  "AL status 0x0011 (INIT + error) while INIT requested"},
        ErrorCase{"InitNoRequest", kInit, std::nullopt, 0x0011, Code::None, RuleId::Esm004,
                  "with no request seen, previous state INIT"},
        ErrorCase{"NothingKnown", std::nullopt, std::nullopt, 0x0011, Code::None, RuleId::Esm004,
                  "with no request seen and no previous state"},
        ErrorCase{"FellOutOfOpNoRequest", kOp, std::nullopt, 0x0014, Code::None, RuleId::Esm003,
                  "(SAFE-OP + error) with no request seen, previous state OP"}),
    [](const ::testing::TestParamInfo<ErrorCase>& row) { return row.param.name; });

TEST(AlTracker, ErrorReportedOncePerEpisode) {
  Harness h;
  h.status(kStation0, kInit);
  h.request(kStation0, kPreOp);
  for (int i = 0; i < 3; ++i) h.status(kStation0, 0x0012);
  EXPECT_EQ(h.count(RuleId::Esm003), 1u) << describe(h.findings);
  h.status(kStation0, 0x0002);  // cleared
  h.status(kStation0, 0x0012);
  h.status(kStation0, 0x0012);
  EXPECT_EQ(h.count(RuleId::Esm003), 2u) << describe(h.findings);
  EXPECT_EQ(h.findings.size(), 2u) << describe(h.findings);
}

// --- broadcasts, addressing and WKC -----------------------------------------------------------

TEST(AlTracker, BroadcastStatusAppliesToAll) {
  Harness h;
  h.assignStations(2);
  h.status(kStation0, kInit);
  h.status(kStation1, kPreOp);
  auto brd = [&h](std::uint16_t value, std::uint16_t wkc = 2) {
    return h.exchange({Dg{ecat::kBrd, 0, physical(0, kRegStatus), Bytes(2, 0), 0}},
                      {Dg{ecat::kBrd, 0, physical(2, kRegStatus), le16(value), wkc}});
  };
  brd(kSafeOp);
  EXPECT_EQ(h.tracker.stateOfStation(kStation0), kSafeOp);
  EXPECT_EQ(h.tracker.stateOfStation(kStation1), kSafeOp);
  brd(kSafeOp | kOp);  // the OR of different states: no state, nothing changes
  EXPECT_EQ(h.tracker.stateOfStation(kStation0), kSafeOp);
  brd(kOp);
  EXPECT_EQ(h.tracker.opEntries(kStation0), 1u);
  EXPECT_EQ(h.tracker.opEntries(kStation1), 1u);
  brd(kOp | 0x10);  // the error of some slave: it names none, nothing is reported
  EXPECT_EQ(h.tracker.stateOfStation(kStation1), kOp);
  brd(kInit, 0);  // nobody answered
  EXPECT_EQ(h.tracker.stateOfStation(kStation1), kOp);
  // A station never addressed has the broadcast state.
  EXPECT_EQ(h.tracker.stateOfStation(0x2000), kOp);
  EXPECT_TRUE(h.findings.empty()) << describe(h.findings);
}

TEST(AlTracker, BroadcastStateBeforeAnySlaveIsKnown) {
  Harness h;
  h.exchange({Dg{ecat::kBrd, 0, physical(0, kRegStatus), Bytes(2, 0), 0}},
             {Dg{ecat::kBrd, 0, physical(2, kRegStatus), le16(kPreOp), 2}});
  EXPECT_EQ(h.tracker.stateOfStation(kStation0), kPreOp);
  // A broadcast request the broadcast state forbids names no slave.
  const auto all =
      h.feed({Dg{ecat::kBwr, 0, physical(0, kRegControl), le16(kOp), 0}}, false, false);
  ASSERT_EQ(all.size(), 1u) << describe(all);
  EXPECT_EQ(all[0].station, std::nullopt);
  EXPECT_NE(all[0].message.find("all slaves (broadcast)"), std::string::npos) << all[0].message;
  // A slave first seen now knows the broadcast state and request.
  const auto err = h.status(kStation0, 0x0012);
  ASSERT_EQ(err.size(), 1u) << describe(err);
  EXPECT_EQ(err[0].rule, RuleId::Esm003);
  EXPECT_NE(err[0].message.find("while OP requested"), std::string::npos) << err[0].message;
}

TEST(AlTracker, AutoIncrementReadMapsThroughTheMastersAdp) {
  Harness h;
  h.assignStations(2);
  h.status(kStation0, kSafeOp);
  h.status(kStation1, kSafeOp);
  // Position 1 is ADP 0xFFFF in the master's copy; two slaves have incremented it to 0x0001.
  const Dg master{ecat::kAprd, 0, physical(apAdp(1), kRegStatus), Bytes(2, 0), 0};
  const Dg back{ecat::kAprd, 0, physical(static_cast<std::uint16_t>(apAdp(1) + 2), kRegStatus),
                le16(kOp), 1};
  h.feed({master}, false, false);
  h.feed({back}, true, true);
  EXPECT_EQ(h.tracker.stateOfStation(kStation1), kOp);
  EXPECT_EQ(h.tracker.opEntries(kStation1), 1u);
  EXPECT_EQ(h.tracker.opEntries(kStation0), 0u);
  EXPECT_EQ(h.tracker.stateOfStation(kStation0), kSafeOp);
  // Unpaired, the returned ADP names nobody: the read is skipped.
  const Dg back0{ecat::kAprd, 0, physical(static_cast<std::uint16_t>(apAdp(0) + 2), kRegStatus),
                 le16(kInit), 1};
  h.feed({back0}, true, false);
  EXPECT_EQ(h.tracker.stateOfStation(kStation0), kSafeOp);
  EXPECT_EQ(h.tracker.stateOfStation(kStation1), kOp);
  EXPECT_TRUE(h.findings.empty()) << describe(h.findings);
}

TEST(AlTracker, ReadWithWkcZeroIsIgnored) {
  Harness h;
  h.status(kStation0, kPreOp);
  h.status(kStation0, kOp, std::nullopt, 0);
  EXPECT_EQ(h.tracker.stateOfStation(kStation0), kPreOp);
  h.status(kStation0, 0x0012, std::nullopt, 0);
  EXPECT_TRUE(h.findings.empty()) << describe(h.findings);
  // A master's copy is never a read, whatever its data says.
  h.feed({Dg{ecat::kFprd, 0, physical(kStation0, kRegStatus), le16(kOp), 0}}, false, false);
  EXPECT_EQ(h.tracker.stateOfStation(kStation0), kPreOp);
}

TEST(AlTracker, LongerReadCoversStatus) {
  Harness h;
  // A read from 0x0120 to 0x0135: control, then status at offset 16, code at offset 20.
  Bytes data(22, 0);
  data[16] = 0x14;
  data[20] = 0x1B;
  const Dg master{ecat::kFprd, 0, physical(kStation0, kRegControl), Bytes(22, 0), 0};
  const Dg back{ecat::kFprd, 0, physical(kStation0, kRegControl), data, 1};
  const auto out = h.exchange({master}, {back});
  EXPECT_EQ(h.tracker.stateOfStation(kStation0), kSafeOp);
  ASSERT_EQ(out.size(), 1u) << describe(out);
  EXPECT_NE(out[0].message.find("AL status code 0x001B (sync manager watchdog)"), std::string::npos)
      << out[0].message;
  // A read that starts after 0x0130 or ends before it covers nothing.
  h.exchange({Dg{ecat::kFprd, 0, physical(kStation1, 0x0131), Bytes(2, 0), 0}},
             {Dg{ecat::kFprd, 0, physical(kStation1, 0x0131), le16(kOp), 1}});
  h.exchange({Dg{ecat::kFprd, 0, physical(kStation1, 0x012E), Bytes(2, 0), 0}},
             {Dg{ecat::kFprd, 0, physical(kStation1, 0x012E), le16(kOp), 1}});
  EXPECT_EQ(h.tracker.stateOfStation(kStation1), std::nullopt);
}

// A frame of cyclic process data and the DC time reaches no AL register; one register datagram
// among them is still seen, wherever it sits and however far before the registers it starts.
struct AmongCase {
  const char* name;
  bool with_status_read;
  std::uint16_t read_from;  // ADO of the FPRD; its data covers AL status at 0x0130
  bool status_first;        // the FPRD before the LRW and the FRMW
};
class AlTrackerAmongCyclic : public ::testing::TestWithParam<AmongCase> {};

TEST_P(AlTrackerAmongCyclic, StatusReadSeen) {
  const AmongCase c = GetParam();
  Harness h;
  const Dg lrw{ecat::kLrw, 0, 0x00010000, Bytes(50, 0), 0};
  const Dg lrw_back{ecat::kLrw, 0, 0x00010000, Bytes(50, 0), 3};
  const Dg dc{ecat::kFrmw, 1, physical(kStation0, 0x0910), Bytes(8, 0), 0};
  const Dg dc_back{ecat::kFrmw, 1, physical(kStation0, 0x0910), Bytes(8, 0), 1};
  std::vector<Dg> master{lrw, dc};
  std::vector<Dg> back{lrw_back, dc_back};
  if (c.with_status_read) {
    const std::size_t size = kRegStatus + 2u - c.read_from;
    Bytes data(size, 0);
    data[kRegStatus - c.read_from] = kOp;
    const Dg read{ecat::kFprd, 2, physical(kStation0, c.read_from), Bytes(size, 0), 0};
    const Dg read_back{ecat::kFprd, 2, physical(kStation0, c.read_from), data, 1};
    master.insert(c.status_first ? master.begin() : master.end(), read);
    back.insert(c.status_first ? back.begin() : back.end(), read_back);
  }
  EXPECT_TRUE(h.exchange(master, back).empty());
  EXPECT_EQ(h.tracker.stateOfStation(kStation0),
            c.with_status_read ? std::optional<std::uint8_t>(kOp) : std::nullopt)
      << c.name;
}

INSTANTIATE_TEST_SUITE_P(AlTracker, AlTrackerAmongCyclic,
                         ::testing::Values(AmongCase{"cyclic only", false, 0, false},
                                           AmongCase{"status read last", true, kRegStatus, false},
                                           AmongCase{"status read first", true, kRegStatus, true},
                                           AmongCase{"read from 0x0000", true, 0x0000, false},
                                           AmongCase{"read from control", true, kRegControl, true}),
                         test::rowName<AmongCase>);

// Every cut of a frame: no read past the captured bytes (ASan), and nothing wrong comes out.
TEST(AlTracker, TruncatedFramesNeverReadPastTheEnd) {
  const Bytes read = frameOf({Dg{ecat::kFprd, 0, physical(kStation0, kRegStatus),
                                 Bytes{0x12, 0x00, 0x00, 0x00, 0x1D, 0x00}, 1}});
  const Bytes write = frameOf({Dg{ecat::kFpwr, 0, physical(kStation0, kRegControl), le16(kOp), 0}});
  const Bytes assign =
      frameOf({Dg{ecat::kApwr, 0, physical(apAdp(0), kRegStation), le16(kStation0), 0}});
  for (std::size_t size = 0; size < read.size(); ++size) {
    SCOPED_TRACE("read cut at " + std::to_string(size));
    Harness h;
    h.status(kStation0, kInit);
    h.feedBytes(read, size, true, false);  // cut: no WKC, so no read
    EXPECT_EQ(h.tracker.stateOfStation(kStation0), kInit);
    EXPECT_TRUE(h.findings.empty()) << describe(h.findings);
  }
  for (std::size_t size = 0; size < write.size(); ++size) {
    SCOPED_TRACE("write cut at " + std::to_string(size));
    Harness h;
    h.status(kStation0, kInit);
    const auto out = h.feedBytes(write, size, false, false);
    // The request is judged once its state byte is captured, and then correctly.
    const bool state_captured = size > test::kChainOffset + ecat::kDatagramHeaderSize;
    ASSERT_EQ(out.size(), state_captured ? 1u : 0u) << describe(out);
    if (state_captured) {
      EXPECT_NE(out[0].message.find("requests OP from known state INIT"), std::string::npos);
    }
  }
  for (std::size_t size = 0; size < assign.size(); ++size) {
    SCOPED_TRACE("assignment cut at " + std::to_string(size));
    Harness h;
    h.feedBytes(assign, size, false, false);
    h.status(kStation0, kInit);
    const auto out = h.exchange({Dg{ecat::kApwr, 0, physical(apAdp(0), kRegControl), le16(kOp), 0}},
                                {Dg{ecat::kApwr, 0, physical(1, kRegControl), le16(kOp), 1}});
    // Only a whole station address joins position 0 to the station.
    const bool whole = size >= assign.size() - ecat::kWkcSize;
    EXPECT_EQ(out.size(), whole ? 1u : 0u) << describe(out);
  }
}

TEST(AlTracker, StationAddressMovesToAnotherSlave) {
  Harness h;
  h.assignStations(2);
  h.status(kStation0, kOp);
  // A new start-up gives position 1 the station address position 0 had.
  h.exchange({Dg{ecat::kApwr, 0, physical(apAdp(1), kRegStation), le16(kStation0), 0}},
             {Dg{ecat::kApwr, 0, physical(1, kRegStation), le16(kStation0), 1}});
  const auto out = h.request(kStation0, kOp);  // position 1's state is not known: no finding
  EXPECT_TRUE(out.empty()) << describe(out);
  EXPECT_EQ(h.tracker.stateOfStation(kStation0), std::nullopt);
}

TEST(AlTracker, MemoryIsBounded) {
  Harness h;
  const std::size_t extra = 10;
  for (std::size_t k = 0; k < AlTracker::kMaxSlaves + extra; ++k) {
    const Dg back{ecat::kFprd, 0, physical(static_cast<std::uint16_t>(k), kRegStatus), le16(kPreOp),
                  1};
    h.feed({back}, true, false);
  }
  EXPECT_EQ(h.tracker.stateOfStation(0), kPreOp);
  EXPECT_EQ(h.tracker.stateOfStation(static_cast<std::uint16_t>(AlTracker::kMaxSlaves - 1)),
            kPreOp);
  EXPECT_EQ(h.tracker.stateOfStation(static_cast<std::uint16_t>(AlTracker::kMaxSlaves)),
            std::nullopt);
  const auto out = h.status(static_cast<std::uint16_t>(AlTracker::kMaxSlaves + 1), 0x0012);
  EXPECT_TRUE(out.empty()) << describe(out);
}

// docs/incidents.md#esm: a status read of one slave leaving or entering OP is an OP change, with
// the master's last request (an incident only when that was OP or unknown).
struct OpChangeCase {
  const char* name;
  std::optional<std::uint16_t> request_after_op;  // an AL control write once the slave is in OP
  std::uint16_t status;                           // the read after it
  bool change;
  std::optional<std::uint8_t> requested;
};

TEST(AlTracker, OpChangesCarryTheRequest) {
  const OpChangeCase cases[] = {
      {"falls to SAFE-OP + error, OP requested", std::nullopt, 0x14, true, kOp},
      {"falls to SAFE-OP, SAFE-OP requested", kSafeOp, kSafeOp, true, kSafeOp},
      {"stays in OP", std::nullopt, kOp, false, std::nullopt},
  };
  for (const OpChangeCase& c : cases) {
    Harness h;
    h.assignStations(1);
    h.status(kStation0, kSafeOp);
    h.request(kStation0, kOp);
    h.status(kStation0, kOp);
    EXPECT_EQ(h.tracker.opChanges().size(), 1u) << c.name << ": entering OP is a change";
    if (c.request_after_op) h.request(kStation0, *c.request_after_op);
    h.status(kStation0, c.status);
    const std::vector<AlOpChange>& changes = h.tracker.opChanges();
    ASSERT_EQ(changes.size(), c.change ? 1u : 0u) << c.name;
    if (!c.change) continue;
    EXPECT_EQ(changes[0].from, kOp) << c.name;
    EXPECT_EQ(changes[0].to, kSafeOp) << c.name;
    EXPECT_EQ(changes[0].slave.station, std::optional<std::uint16_t>(kStation0)) << c.name;
    EXPECT_EQ(changes[0].requested, c.requested) << c.name;
  }
}

// One frame's slave addressing (slave_directory.hpp FrameAddressing), which the AL tracker and the
// DC clock share: a returned copy's auto-increment address is the master copy's just before it.
struct AddressingCase {
  std::string name;
  std::optional<Dg> master;  // the frame before, a master copy
  Dg dg;                     // the frame addressed
  bool returned;
  bool paired;
  SlaveTarget target;
  std::uint16_t value;
  bool writes;  // takesWrites()
  bool read;    // takesRead(dg)
};
class FrameAddressingRows : public ::testing::TestWithParam<AddressingCase> {};
TEST_P(FrameAddressingRows, Addresses) {
  const AddressingCase& c = GetParam();
  FrameAddressing addressing;
  std::vector<Bytes> kept;  // the walked frames' bytes outlive their walks
  auto frameOf = [&kept](const Dg& dg) {
    FrameBuilder builder;
    builder.add(dg);
    kept.push_back(builder.bytes());
    return test::walk(kept.back());
  };
  if (c.master) {
    const test::Walked w = frameOf(*c.master);
    addressing.beginFrame(*w.frame, false, false);
  }
  const test::Walked w = frameOf(c.dg);
  addressing.beginFrame(*w.frame, c.returned, c.paired);
  const SlaveAddress address = addressing.addressOf(w.frame->datagrams[0], 0);
  EXPECT_EQ(address.target, c.target);
  EXPECT_EQ(address.value, c.value);
  EXPECT_EQ(addressing.takesWrites(), c.writes);
  EXPECT_EQ(addressing.takesRead(w.frame->datagrams[0]), c.read);
}
INSTANTIATE_TEST_SUITE_P(
    AlTracker, FrameAddressingRows,
    ::testing::Values(
        AddressingCase{"configured address", std::nullopt,
                       Dg{ecat::kFprd, 0, physical(kStation0, kRegStatus), le16(0), 0}, false,
                       false, SlaveTarget::Station, kStation0, true, false},
        AddressingCase{"broadcast", std::nullopt,
                       Dg{ecat::kBrd, 0, physical(0, kRegStatus), le16(0), 0}, false, false,
                       SlaveTarget::All, 0, true, false},
        AddressingCase{"master copy's auto-increment address", std::nullopt,
                       Dg{ecat::kAprd, 0, physical(0xFFFE, kRegStatus), le16(0), 0}, false, false,
                       SlaveTarget::Position, 2, true, false},
        AddressingCase{"paired returned copy takes the master copy's ADP",
                       Dg{ecat::kAprd, 0, physical(0xFFFE, kRegStatus), le16(0), 0},
                       Dg{ecat::kAprd, 0, physical(0x0001, kRegStatus), le16(kOp), 1}, true, true,
                       SlaveTarget::Position, 2, false, true},
        AddressingCase{"returned copy without its master copy names no position",
                       Dg{ecat::kAprd, 0, physical(0xFFFE, kRegStatus), le16(0), 0},
                       Dg{ecat::kAprd, 0, physical(0x0001, kRegStatus), le16(kOp), 1}, true, false,
                       SlaveTarget::None, 0, true, true},
        AddressingCase{"master copy of another command names no position",
                       Dg{ecat::kApwr, 0, physical(0xFFFE, kRegControl), le16(kOp), 0},
                       Dg{ecat::kAprd, 0, physical(0x0001, kRegStatus), le16(kOp), 1}, true, true,
                       SlaveTarget::None, 0, false, true},
        AddressingCase{"read no slave answered is not taken",
                       Dg{ecat::kFprd, 0, physical(kStation1, kRegStatus), le16(0), 0},
                       Dg{ecat::kFprd, 0, physical(kStation1, kRegStatus), le16(0), 0}, true, true,
                       SlaveTarget::Station, kStation1, false, false},
        AddressingCase{"logical command addresses no slave", std::nullopt,
                       Dg{ecat::kLrw, 0, 0x10000, Bytes(4, 0), 3}, true, false, SlaveTarget::None,
                       0, true, false}),
    test::rowName<AddressingCase>);

}  // namespace
}  // namespace ncservo
