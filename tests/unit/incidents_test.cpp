// The incident detector (docs/incidents.md): one row per cause row of the table firing, and the
// near misses that must fall to a later row; the bus outage; what came before; the recovery; the
// documented cause table.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "ncservo/incidents/causes.hpp"
#include "ncservo/incidents/incident_detector.hpp"
#include "validator_driver.hpp"

namespace ncservo::test {
namespace {

// SEW bits (docs/protocol.md §4) and SSW bits (§3) the rows set.
constexpr std::uint32_t kFollowerErr = 0x80000;
constexpr std::uint32_t kEcatWatchdog = 0x400000;
constexpr std::uint32_t kI2t = 0x4;
constexpr std::uint32_t kCurrErr = 0x40;
constexpr std::uint32_t kBvErr = 0x20;
constexpr std::uint32_t kOverSpeed = 0x800000;
constexpr std::uint32_t kParamChecksum = 0x20000;
constexpr std::uint32_t kPdpint = 0x10000;  // a cause no row names
constexpr std::uint32_t kTempWarning = 0x800;

constexpr std::int64_t kFault = 300;  // the cycle whose returned copy shows the fault
constexpr std::int64_t kCleared = 320;

// One running axis that faults at kFault with `sew` (the summary bit added) and is cleared at
// kCleared, still enabled; `chain` adds what comes before.
Script faultScript(std::uint32_t sew, const std::function<void(Script&)>& chain = nullptr,
                   std::int64_t fault = kFault) {
  Script s(fault + 60);
  s.sew(fault, fault + (kCleared - kFault), kSummary | sew);
  if (chain) chain(s);
  return s;
}

struct CauseRow {
  const char* name;
  Script script;
  const char* cause;
  const char* text;  // a part of the cause's text
};

std::vector<CauseRow> causeRows() {
  return {
      {"watchdog bit", faultScript(kEcatWatchdog), "communication-loss", "ECatWatchDog (E31)"},
      {"lost cycles 10 ms before",
       faultScript(kFollowerErr, [](Script& s) { s.missing(289, 292); }), "communication-loss",
       "cycles lost"},
      {"wrong WKC 20 ms before", faultScript(kFollowerErr, [](Script& s) { s.wkc(280, 281, 1); }),
       "communication-loss", "with a wrong WKC"},
      {"lost cycles 150 ms before: near miss",
       faultScript(kFollowerErr, [](Script& s) { s.missing(149, 152); }), "following-error",
       "FollowerErr (E09)"},
      {"I2t_Endat", faultScript(kI2t), "overtemperature", "I2t_Endat (E19)"},
      {"TempWarning 50 ms before",
       faultScript(kFollowerErr,
                   [](Script& s) { s.ssw(250, kFault + 60, kSswRunning | kTempWarning); }),
       "overtemperature", "SSW.TempWarning from frame"},
      {"temperature 41 to 96 C",
       faultScript(
           kCurrErr,
           [](Script& s) {
             s.msg(0, kFault + 60, 4).msgData(0, 200, 41.0F).msgData(200, kFault + 60, 96.0F);
           }),
       "overtemperature", "motor temperature 41 \u2192 96 \u00b0C over"},
      // Flat for most of the minute, then a surge: told from where it left 35 C, not from the
      // first reading (docs/incidents.md#overtemperature).
      {"temperature flat then a surge",
       faultScript(kCurrErr,
                   [](Script& s) {
                     s.msg(0, kFault + 60, 4)
                         .msgData(0, 280, 35.0F)
                         .msgData(280, 290, 65.0F)
                         .msgData(290, kFault + 60, 95.0F);
                   }),
       "overtemperature", "motor temperature 35 \u2192 95 \u00b0C over 20 ms from frame 560"},
      {"temperature up 5 C: near miss",
       faultScript(
           kCurrErr,
           [](Script& s) {
             s.msg(0, kFault + 60, 4).msgData(0, 200, 41.0F).msgData(200, kFault + 60, 46.0F);
           }),
       "overcurrent", "CurrErr (E06)"},
      {"step 50 ms before FollowerErr",
       faultScript(kFollowerErr,
                   [](Script& s) { s.ssp(0, 250, 1000).ssp(250, kFault + 60, 50000); }),
       "following-error-after-step", "after an SSP step 1000 \u2192 50000"},
      {"step 150 ms before FollowerErr: near miss",
       faultScript(kFollowerErr,
                   [](Script& s) { s.ssp(0, 150, 1000).ssp(150, kFault + 60, 50000); }),
       "following-error", "no set-point step"},
      {"ramp start 50 ms before: near miss",
       faultScript(kFollowerErr,
                   [](Script& s) {
                     s.ssp(0, 250, 0);
                     for (std::int64_t k = 250; k < kFault + 60; ++k) {
                       s.ssp(k, k + 1, static_cast<std::int32_t>(1000 * (k - 249)));
                     }
                   }),
       "following-error", "no set-point step"},
      {"FollowerErr", faultScript(kFollowerErr), "following-error", "FollowerErr (E09)"},
      {"CurrErr with current",
       faultScript(kCurrErr,
                   [](Script& s) { s.msg(0, kFault + 60, 1).msgData(0, kFault + 60, 12.5F); }),
       "overcurrent", "motor current 12.5 A 1 ms before (frame 600)"},
      // Message codes take turns: the last current reading is 25 cycles old, and says so.
      {"CurrErr with an old current",
       faultScript(kCurrErr,
                   [](Script& s) {
                     s.msg(0, 276, 1).msgData(0, 276, 12.5F);
                     s.msg(276, kFault + 60, 3).msgData(276, kFault + 60, 560.0F);
                   }),
       "overcurrent", "motor current 12.5 A 25 ms before (frame 552)"},
      {"BVErr", faultScript(kBvErr), "bus-voltage", "BVErr (E05)"},
      {"EncoderErr", faultScript(kEncoderErr), "encoder", "EncoderErr (E01)"},
      {"NoEncoder 20 ms before",
       faultScript(kPdpint, [](Script& s) { s.ssw(280, kFault + 60, kSswRunning | kNoEncoder); }),
       "encoder", "SSW.NoEncoder from frame"},
      {"NoEncoder 150 ms before: near miss",
       faultScript(kPdpint, [](Script& s) { s.ssw(150, kFault + 60, kSswRunning | kNoEncoder); }),
       "unknown", "PDPINT (E16)"},
      {"OverSpeed", faultScript(kOverSpeed), "overspeed", "OverSpeed (E11)"},
      {"PTBLCHKSErr", faultScript(kParamChecksum), "configuration", "PTBLCHKSErr (E30)"},
      {"SE-001 15 ms before", faultScript(kPdpint, [](Script& s) { s.scw(280, 285, kScwOff); }),
       "nc-command", "SE-001 illegal-enable-edge at frame"},
      {"SE-001 150 ms before: near miss",
       faultScript(kPdpint, [](Script& s) { s.scw(145, 150, kScwOff); }), "unknown",
       "PDPINT (E16)"},
      {"PDPINT", faultScript(kPdpint), "unknown", "PDPINT (E16)"},
  };
}

TEST(Incidents, EachCauseRowFiresAndNearMissesFallThrough) {
  for (const CauseRow& row : causeRows()) {
    ValidatorDriver driver;
    driver.run(row.script);
    const std::vector<Incident>& incidents = driver.incidents().incidents();
    ASSERT_EQ(incidents.size(), 1u) << row.name;
    const Incident& incident = incidents.front();
    EXPECT_EQ(incident.kind, IncidentKind::DriveFault) << row.name;
    EXPECT_EQ(incident.axis, std::optional<std::uint16_t>(0)) << row.name;
    EXPECT_EQ(incident.at.frame, driver.frameOf(R(kFault))) << row.name;
    EXPECT_STREQ(causeDef(incident.cause).name, row.cause)
        << row.name << ": " << incident.cause_text;
    EXPECT_NE(incident.cause_text.find(row.text), std::string::npos)
        << row.name << ": " << incident.cause_text;
  }
}

// sync-error (docs/incidents.md#sync-error) needs the AL status code of the axis's slave: the
// station-addressed axis, its AL status polled every 10 cycles in OP with code 0 until `read_at`,
// whose read has `state` and `code` and is the last; SEW `sew` from kFault to kCleared.
struct SyncRow {
  const char* name;
  std::int64_t read_at;
  std::uint16_t state;
  std::uint16_t code;
  std::uint32_t sew;
  IncidentKind kind;  // the incident the row judges
  const char* cause;
};

constexpr std::uint16_t kAlOp = 0x08;
constexpr std::uint16_t kAlSafeOpError = 0x14;

std::vector<SyncRow> syncRows() {
  using K = IncidentKind;
  return {
      {"ESM: SAFE-OP with 0x001A synchronization error", kFault, kAlSafeOpError, 0x001A, 0, K::Esm,
       "sync-error"},
      {"ESM: SAFE-OP with 0x0034 DC sync timeout", kFault, kAlSafeOpError, 0x0034, 0, K::Esm,
       "sync-error"},
      // No sync code: the next row with evidence, the NC's outputs still enabled outside OP
      // (ESM-002, party NC) on the same frame.
      {"ESM: SAFE-OP with 0x0011, no sync code", kFault, kAlSafeOpError, 0x0011, 0, K::Esm,
       "nc-command"},
      {"drive fault, 0x001B read at the fault", kFault, kAlSafeOpError, 0x001B, kPdpint,
       K::DriveFault, "sync-error"},
      {"drive fault, 0x001A read 100 ms before", kFault - 100, kAlSafeOpError, 0x001A, kPdpint,
       K::DriveFault, "sync-error"},
      {"drive fault, 0x001A read 101 ms before", kFault - 101, kAlSafeOpError, 0x001A, kPdpint,
       K::DriveFault, "unknown"},
      {"drive fault, code 0 read at the fault", kFault, kAlOp, 0, kPdpint, K::DriveFault,
       "unknown"},
      {"drive fault with ECatWatchDog: communication-loss first", kFault, kAlSafeOpError, 0x001B,
       kEcatWatchdog, K::DriveFault, "communication-loss"},
  };
}

TEST(Incidents, SyncErrorFromTheSlavesAlStatusCode) {
  for (const SyncRow& row : syncRows()) {
    SCOPED_TRACE(row.name);
    ValidatorDriver driver(RuleSettings{}, stationAxis());
    std::uint64_t read_frame = 0;
    for (std::int64_t k = 0; k < kFault + 60; ++k) {
      const std::int64_t t = kEpochNs + k * kMs;
      const std::uint32_t sew = k >= kFault && k < kCleared ? kSummary | row.sew : 0;
      std::optional<std::uint16_t> al, code;
      if (k == row.read_at) {
        al = row.state;
        code = row.code;
      } else if (k < row.read_at && k % 10 == 0) {
        al = kAlOp;
        code = 0;
      }
      driver.feed(stationFrame(kScwRunning, kSswRunning, al, false, 0, code), t);
      driver.feed(stationFrame(kScwRunning, kSswRunning, al, true, sew, code), t + 20 * kUs);
      if (k == row.read_at) read_frame = driver.frames();
    }
    driver.finish();
    const std::vector<Incident>& incidents = driver.incidents().incidents();
    const auto incident = std::find_if(incidents.begin(), incidents.end(),
                                       [&](const Incident& i) { return i.kind == row.kind; });
    ASSERT_NE(incident, incidents.end()) << incidents.size() << " incidents";
    EXPECT_EQ(incident->axis, std::optional<std::uint16_t>(0));
    EXPECT_STREQ(causeDef(incident->cause).name, row.cause) << incident->cause_text;
    if (incident->cause != CauseId::SyncError) continue;
    EXPECT_NE(incident->cause_text.find(fmt::format("AL status code 0x{:04X}", row.code)),
              std::string::npos)
        << incident->cause_text;
    EXPECT_TRUE(std::any_of(incident->evidence.begin(), incident->evidence.end(),
                            [&](const IncidentEvidence& e) { return e.at.frame == read_frame; }))
        << "the read is the evidence";
  }
}

// link-fault (docs/incidents.md#link-fault): the station-addressed axis loses the returned copies
// of cycles 295-297 and faults (PDPINT) at kFault; the master reads its slave's ESC error
// counters (0x0300, 20 bytes) at `first_read` and at `second_read`, the second with `rx` RX
// errors at port 0 and `lost` lost links at port 0.
struct LinkRow {
  const char* name;
  std::int64_t second_read;
  std::uint8_t rx;
  std::uint8_t lost;
  const char* cause;
  const char* text;  // a part of the cause's text
  std::int64_t first_read = 100;
};

std::vector<LinkRow> linkRows() {
  return {
      {"read before the fault", kFault - 2, 5, 0, "link-fault", "5 RX errors at the read of frame"},
      {"read 5 s after the fault", kFault + 5000, 5, 0, "link-fault", "since frame"},
      // The read comes 100 us after its cycle's returned copy: 9.9991 s and 10.0001 s.
      {"read just under 10 s after the fault", kFault + 9'999, 5, 0, "link-fault", "; "},
      {"read just over 10 s after the fault: too late", kFault + 10'000, 5, 0, "communication-loss",
       "cycles lost"},
      {"no rise at the second read", kFault + 10, 0, 0, "communication-loss", "cycles lost"},
      {"the read before came after the failures began", kFault + 10, 5, 0, "communication-loss",
       "cycles lost", 296},
      {"a lost link", kFault + 10, 0, 1, "link-fault", "1 lost link at the read of frame"},
  };
}

Bytes counterRead(std::uint8_t rx, std::uint8_t lost, bool returned) {
  Bytes counters(ecat::kErrorCountersSize, 0);
  if (returned) {
    counters[0x01] = rx;    // 0x0301: RX errors at port 0
    counters[0x10] = lost;  // 0x0310: lost links at port 0
  }
  FrameBuilder builder;
  builder.add(Dg{ecat::kFprd, 9, physical(kStation, ecat::kRegInvalidFrame0), std::move(counters),
                 static_cast<std::uint16_t>(returned ? 1 : 0)});
  return builder.bytes();
}

TEST(Incidents, LinkFaultFromTheEscCountersReadUpTo10sLater) {
  for (const LinkRow& row : linkRows()) {
    SCOPED_TRACE(row.name);
    ValidatorDriver driver(RuleSettings{}, stationAxis());
    std::uint64_t read_frame = 0;
    bool final_before_read = true;
    bool revised_at_read = false;
    for (std::int64_t k = 0; k < std::max(row.second_read, kFault) + 20; ++k) {
      const std::int64_t t = kEpochNs + k * kMs;
      const std::uint32_t sew = k >= kFault && k < kCleared ? kSummary | kPdpint : 0;
      driver.feed(stationFrame(kScwRunning, kSswRunning, std::nullopt, false), t);
      if (k < 295 || k > 297) {
        driver.feed(stationFrame(kScwRunning, kSswRunning, std::nullopt, true, sew), t + 20 * kUs);
      }
      if (k == row.first_read || k == row.second_read) {
        const bool second = k == row.second_read;
        if (second && k > kFault && !driver.incidents().incidents().empty()) {
          final_before_read = driver.incidents().causeFinal(0);
        }
        driver.feed(counterRead(second ? row.rx : 0, second ? row.lost : 0, false), t + 100 * kUs);
        driver.feed(counterRead(second ? row.rx : 0, second ? row.lost : 0, true), t + 120 * kUs);
        if (second) {
          read_frame = driver.frames();
          const std::vector<std::size_t>& revised = driver.incidents().revised();
          revised_at_read = std::find(revised.begin(), revised.end(), 0u) != revised.end();
        }
      }
    }
    driver.finish();
    const std::vector<Incident>& incidents = driver.incidents().incidents();
    ASSERT_EQ(incidents.size(), 1u);
    const Incident& incident = incidents.front();
    EXPECT_EQ(incident.kind, IncidentKind::DriveFault);
    EXPECT_STREQ(causeDef(incident.cause).name, row.cause) << incident.cause_text;
    EXPECT_NE(incident.cause_text.find(row.text), std::string::npos) << incident.cause_text;
    EXPECT_TRUE(driver.incidents().causeFinal(0)) << "final once the capture ended";
    if (incident.cause != CauseId::LinkFault) continue;
    EXPECT_NE(incident.cause_text.find("the link into station 0x03E9 port 0"), std::string::npos)
        << incident.cause_text;
    EXPECT_NE(incident.cause_text.find("cycles lost"), std::string::npos) << incident.cause_text;
    EXPECT_TRUE(std::any_of(incident.evidence.begin(), incident.evidence.end(),
                            [&](const IncidentEvidence& e) { return e.at.frame == read_frame; }))
        << "the read is the evidence";
    EXPECT_EQ(incident.ordinal, 1u);
    if (row.second_read > kFault) {
      EXPECT_FALSE(final_before_read) << "the cause waited for the read";
      EXPECT_TRUE(revised_at_read) << "the read's frame revised it";
    }
  }
}

// The drive's own words (docs/incidents.md#the-drives-own-words): the station-addressed axis with
// its mailbox (SM0 0x1000, SM1 0x1080 from the start-up), PDPINT at kFault. Emergencies read 150
// and 50 ms before it, an SDO upload of 2000h:0 100 ms after, of 1003h:1 2 s after, and an
// emergency 11 s after: the evidence holds the emergency of the 100 ms before and the 1003h entry,
// the latter added at its read's frame.
TEST(Incidents, TheDrivesOwnWordsAreEvidence) {
  constexpr std::uint16_t kOut = 0x1000, kIn = 0x1080;
  ValidatorDriver driver(RuleSettings{}, stationAxis());
  std::int64_t t = 0;
  // The master copy (a read's data still empty), then the returned copy with WKC 1.
  auto send = [&](Dg dg, bool read) {
    const Bytes data = dg.data;
    if (read) dg.data = Bytes(data.size(), 0);
    FrameBuilder master;
    master.add(dg);
    driver.feed(master.bytes(), t += 10 * kUs);
    dg.data = data;
    dg.wkc = 1;
    FrameBuilder returned;
    returned.add(dg);
    driver.feed(returned.bytes(), t += 10 * kUs);
  };
  auto write = [&](const Bytes& mailbox) {
    send(Dg{ecat::kFpwr, 5, physical(kStation, kOut), mailbox, 0}, false);
  };
  auto read = [&](const Bytes& mailbox) {
    send(Dg{ecat::kFprd, 6, physical(kStation, kIn), mailbox, 0}, true);
  };
  std::uint64_t history_frame = 0;
  std::vector<std::size_t> revised_there;
  std::uint8_t counter = 0;
  auto next = [&] { return static_cast<std::uint8_t>(counter++ % 7 + 1); };
  for (std::int64_t k = 0; k < kFault + 11'100; ++k) {
    t = kEpochNs + k * kMs;
    const std::uint32_t sew = k >= kFault && k < kCleared ? kSummary | kPdpint : 0;
    driver.feed(stationFrame(kScwRunning, kSswRunning, std::nullopt, false), t);
    driver.feed(stationFrame(kScwRunning, kSswRunning, std::nullopt, true, sew), t += 20 * kUs);
    if (k == 1) {  // the start-up's SM0 and SM1 in mailbox mode
      send(Dg{ecat::kFpwr, 4, physical(kStation, ecat::kRegSyncManager0),
              concat({smBlock(kOut, kMailboxArea, 0x26), smBlock(kIn, kMailboxArea, 0x22)}), 0},
           false);
    }
    if (k == kFault - 150) read(mbx(3, next(), coe(1, emcy(0x5530, 0x01, {0, 0, 0, 0, 0}))));
    if (k == kFault - 50) read(mbx(3, next(), coe(1, emcy(0x8611, 0x21, {0x0D, 0, 0, 0, 0}))));
    if (k == kFault + 100) {
      write(mbx(3, next(), coe(2, sdo(0x40, 0x2000, 0, 0))));
      read(mbx(3, next(), coe(3, sdo(0x4F, 0x2000, 0, 7))));
    }
    if (k == kFault + 2000) {
      write(mbx(3, next(), coe(2, sdo(0x40, 0x1003, 1, 0))));
      read(mbx(3, next(), coe(3, sdo(0x43, 0x1003, 1, 0x0D218611))));
      history_frame = driver.frames();
      revised_there = driver.incidents().revised();
    }
    if (k == kFault + 11'000) read(mbx(3, next(), coe(1, emcy(0x2310, 0x03, {0, 0, 0, 0, 0}))));
  }
  driver.finish();
  const std::vector<Incident>& incidents = driver.incidents().incidents();
  ASSERT_EQ(incidents.size(), 1u);
  std::string evidence;
  for (const IncidentEvidence& e : incidents[0].evidence) {
    evidence += fmt::format("frame {} {}\n", e.at.frame, e.what);
  }
  EXPECT_NE(evidence.find("drive: emergency 0x8611"), std::string::npos) << evidence;
  EXPECT_NE(evidence.find(fmt::format("frame {} drive: SDO upload 0x1003:1", history_frame)),
            std::string::npos)
      << evidence;
  for (const char* outside : {"0x5530", "0x2000", "0x2310"}) {
    EXPECT_EQ(evidence.find(outside), std::string::npos) << outside << "\n" << evidence;
  }
  EXPECT_EQ(revised_there, std::vector<std::size_t>{0}) << "revised at the history's read";
  EXPECT_STREQ(causeDef(incidents[0].cause).name, "unknown") << "words are evidence, not a cause";
}

// Every row of the table is reached by some row above.
TEST(Incidents, EveryCauseRowIsTested) {
  std::vector<std::string> tested;
  for (const CauseRow& row : causeRows()) tested.push_back(row.cause);
  for (const SyncRow& row : syncRows()) tested.push_back(row.cause);
  for (const LinkRow& row : linkRows()) tested.push_back(row.cause);
  for (const CauseDef& cause : kCauses) {
    EXPECT_NE(std::find(tested.begin(), tested.end(), cause.name), tested.end()) << cause.name;
  }
}

// docs/incidents.md's "looks back" of each cause row, in cycles of the scripts' 1 ms (0: at the
// fault): the documented numbers, which the windows are tested on.
std::map<std::string, std::int64_t> documentedWindows() {
  std::ifstream doc(std::string(NCSERVO_DOCS_DIR) + "/incidents.md");
  EXPECT_TRUE(doc) << "docs/incidents.md";
  std::map<std::string, std::int64_t> windows;
  std::string line;
  bool causes = false;
  while (std::getline(doc, line)) {
    if (line.rfind("## ", 0) == 0) causes = line == "## Causes";
    if (!causes || line.rfind("| `", 0) != 0) continue;
    const std::string id = line.substr(3, line.find('`', 3) - 3);
    const std::string back = line.substr(line.rfind(" | ") + 3);
    std::istringstream words(back);
    std::int64_t n = 0;
    std::string unit;
    words >> n >> unit;
    windows[id] = unit == "s" ? n * 1000 : unit == "ms" ? n : 0;
  }
  return windows;
}

// A cause row's evidence placed at a cycle; the fault, and the row it falls to when the evidence
// is one cycle older than the window.
struct WindowEdgeRow {
  const char* cause;
  std::uint32_t sew;
  std::function<void(Script&, std::int64_t evidence, std::int64_t end)> place;
  const char* outside;
};

std::vector<WindowEdgeRow> windowEdgeRows() {
  return {
      {"communication-loss", kFollowerErr,
       [](Script& s, std::int64_t e, std::int64_t) { s.wkc(e, e + 1, 1); }, "following-error"},
      {"overtemperature", kCurrErr,
       [](Script& s, std::int64_t e, std::int64_t) { s.ssw(e, e + 1, kSswRunning | kTempWarning); },
       "overcurrent"},
      {"following-error-after-step", kFollowerErr,
       [](Script& s, std::int64_t e, std::int64_t end) { s.ssp(0, e, 1000).ssp(e, end, 50000); },
       "following-error"},
      {"encoder", kPdpint,
       [](Script& s, std::int64_t e, std::int64_t end) { s.ssw(e, end, kSswRunning | kNoEncoder); },
       "unknown"},
      {"nc-command", kPdpint,
       [](Script& s, std::int64_t e, std::int64_t) { s.scw(e - 5, e, kScwOff); }, "unknown"},
  };
}

std::string causeOf(const WindowEdgeRow& row, std::int64_t fault, std::int64_t evidence) {
  const std::int64_t end = fault + 60;
  ValidatorDriver driver;
  driver.run(faultScript(
      row.sew, [&](Script& s) { row.place(s, evidence, end); }, fault));
  const std::vector<Incident>& incidents = driver.incidents().incidents();
  if (incidents.size() != 1) return std::to_string(incidents.size()) + " incidents";
  return causeDef(incidents.front().cause).name;
}

// Evidence exactly the documented window before the fault counts; one cycle more does not.
TEST(Incidents, EachCauseWindowEndsOnItsDocumentedNumber) {
  const std::map<std::string, std::int64_t> windows = documentedWindows();
  const std::vector<WindowEdgeRow> rows = windowEdgeRows();
  for (const WindowEdgeRow& row : rows) {
    ASSERT_TRUE(windows.count(row.cause)) << row.cause;
    const std::int64_t window = windows.at(row.cause);
    const std::int64_t fault = window + 100;
    EXPECT_EQ(causeOf(row, fault, fault - window), row.cause) << row.cause << ": at the edge";
    EXPECT_EQ(causeOf(row, fault, fault - window - 1), row.outside)
        << row.cause << ": one cycle beyond";
  }
  for (const auto& entry : windows) {
    const bool tested = std::any_of(rows.begin(), rows.end(),
                                    [&](const WindowEdgeRow& r) { return r.cause == entry.first; });
    // sync-error's edge: its rows "100 ms before" and "101 ms before" above; link-fault's 100 ms
    // are communication-loss's, and its wait of 10 s its rows above.
    EXPECT_TRUE(entry.second == 0 || tested || entry.first == "sync-error" ||
                entry.first == "link-fault")
        << entry.first << " looks back, but no row tests its edge";
  }
}

TEST(Incidents, ChainEvidenceRecoveryAndBefore) {
  Script s(kFault + 80);
  s.msg(0, 100, 1).msgData(0, 100, 4.1F);
  s.msg(100, 200, 4).msgData(100, 200, 41.5F);
  s.msg(200, 250, 3).msgData(200, 250, 560.0F);
  s.msg(250, kFault + 80, 0).msgData(250, kFault + 80, 300.0F);
  s.missing(291, 294);  // 3 cycles: within telegram_failure_limit, no outage
  s.sew(kFault, kCleared, kSummary | kEcatWatchdog);
  s.ssw(kFault, kCleared + 20, kSswReady);  // disabled by the fault, enabled again later
  ValidatorDriver driver;
  driver.run(s);
  const std::vector<Incident>& incidents = driver.incidents().incidents();
  ASSERT_EQ(incidents.size(), 1u);
  const Incident& incident = incidents.front();
  EXPECT_EQ(incident.cause, CauseId::CommunicationLoss);
  // Cycles 291-293 have no copy at all: they lie between cycle 290's master copy (frame 581; its
  // returned copy is 582) and cycle 294's (frame 583).
  EXPECT_NE(incident.cause_text.find("3 cycles lost (between frames 581 and 583)"),
            std::string::npos)
      << incident.cause_text;
  EXPECT_NE(incident.cause_text.find("then ECatWatchDog (E31)"), std::string::npos)
      << incident.cause_text;
  ASSERT_EQ(incident.errors.size(), 1u);
  EXPECT_EQ(sewBitName(*incident.errors[0]), "ecat_watchdog");
  EXPECT_STREQ(incident.errors[0]->display, "E31");
  EXPECT_EQ(incident.errors[0]->canopen, 0x8100);
  ASSERT_TRUE(incident.before[0] && incident.before[1] && incident.before[2] && incident.before[3]);
  EXPECT_NEAR(*incident.before[0], 4.1, 1e-5);    // motor current
  EXPECT_NEAR(*incident.before[1], 41.5, 1e-5);   // temperature
  EXPECT_NEAR(*incident.before[2], 560.0, 1e-5);  // bus voltage
  EXPECT_NEAR(*incident.before[3], 300.0, 1e-5);  // speed
  bool com002 = false;
  for (const IncidentEvidence& e : incident.evidence) {
    EXPECT_LE(e.at.frame, incident.at.frame) << e.what;
    com002 = com002 || e.what.rfind("COM-002", 0) == 0;
  }
  EXPECT_TRUE(com002) << "the COM-002 finding is evidence";
  ASSERT_TRUE(incident.error_clear && incident.reenabled);
  EXPECT_EQ(incident.error_clear->frame, driver.frameOf(R(kCleared)));
  EXPECT_EQ(incident.reenabled->frame, driver.frameOf(R(kCleared + 20)));
  EXPECT_EQ(incident.end.frame, incident.reenabled->frame);
}

TEST(Incidents, NoRecoveryEndsAtTheCapturesLastFrame) {
  Script s(kFault + 40);
  s.sew(kFault, kFault + 40, kSummary | kFollowerErr);
  ValidatorDriver driver;
  driver.run(s);
  ASSERT_EQ(driver.incidents().incidents().size(), 1u);
  const Incident& incident = driver.incidents().incidents().front();
  EXPECT_FALSE(incident.error_clear);
  EXPECT_FALSE(incident.reenabled);
  EXPECT_EQ(incident.end.frame, driver.frames());
}

// docs/incidents.md#communication-loss: the frames named are the master copies that got no
// returned copy, first to last, as stock Wireshark shows them unanswered.
TEST(Incidents, NameTheMasterCopiesThatWereNotReturned) {
  Script s(kFault + 80);
  s.noReturned(291, 294);  // cycles 291-293: master copies 583, 584, 585, none returned
  s.sew(kFault, kCleared, kSummary | kEcatWatchdog);
  s.ssw(kFault, kCleared + 20, kSswReady);
  ValidatorDriver driver;
  driver.run(s);
  ASSERT_EQ(driver.incidents().incidents().size(), 1u);
  const Incident& incident = driver.incidents().incidents().front();
  EXPECT_NE(incident.cause_text.find("3 cycles lost (frames 583-585)"), std::string::npos)
      << incident.cause_text;
  ASSERT_FALSE(incident.evidence.empty());
  EXPECT_EQ(incident.evidence.front().at.frame, 583u) << incident.evidence.front().what;
}

TEST(Incidents, NoFaultNoIncident) {
  ValidatorDriver driver;
  driver.run(Script(400).missing(200, 202));
  EXPECT_TRUE(driver.incidents().incidents().empty());
}

struct OutageRow {
  const char* name;
  std::int64_t missing;  // cycles of every axis
  bool outage;
};

TEST(Incidents, BusOutageWhenEveryAxisFailsBeyondTheLimit) {
  for (const OutageRow& row : {OutageRow{"10 cycles lost", 10, true},
                               OutageRow{"2 cycles lost: within the limit", 2, false}}) {
    Script s(300);
    s.axes(2).missing(200, 200 + row.missing);
    ValidatorDriver driver;
    driver.run(s);
    const std::vector<Incident>& incidents = driver.incidents().incidents();
    if (!row.outage) {
      EXPECT_TRUE(incidents.empty()) << row.name;
      continue;
    }
    ASSERT_EQ(incidents.size(), 1u) << row.name;
    const Incident& incident = incidents.front();
    EXPECT_EQ(incident.kind, IncidentKind::BusOutage) << row.name;
    EXPECT_FALSE(incident.axis) << row.name;
    EXPECT_EQ(incident.at.frame, driver.frameOf(M(200 + row.missing))) << row.name;
    EXPECT_EQ(incident.cause, CauseId::CommunicationLoss) << row.name;
    EXPECT_NE(incident.cause_text.find("every axis failing: 10 cycles lost"), std::string::npos)
        << incident.cause_text;
    EXPECT_TRUE(incident.recovered) << row.name;
    EXPECT_GT(incident.end.frame, incident.at.frame) << row.name;
  }
}

// docs/incidents.md holds the cause table as the library has it: the same rows in the same order.
TEST(Incidents, DocumentedCauseTableIsTheLibrarys) {
  std::ifstream doc(std::string(NCSERVO_DOCS_DIR) + "/incidents.md");
  ASSERT_TRUE(doc) << "docs/incidents.md";
  std::vector<std::string> documented;
  std::string line;
  bool causes = false;  // in the section "## Causes"
  while (std::getline(doc, line)) {
    if (line.rfind("## ", 0) == 0) causes = line == "## Causes";
    if (causes && line.rfind("| `", 0) == 0) documented.push_back(line);
  }
  std::vector<std::string> expected;
  for (const CauseDef& cause : kCauses) {
    const std::string window = cause.window_ns == 0 ? "at the fault"
                               : cause.window_ns % (1000 * kMs) == 0
                                   ? std::to_string(cause.window_ns / (1000 * kMs)) + " s"
                                   : std::to_string(cause.window_ns / kMs) + " ms";
    expected.push_back("| `" + std::string(cause.name) + "` | " + cause.when + " | " + window +
                       " |");
  }
  EXPECT_EQ(documented, expected);
}

}  // namespace
}  // namespace ncservo::test
