// What `ncservo simulate` writes of a capturing PC (capture_shapes.hpp, docs/simulate.md
// #the-capturing-pc): the stamp transforms and their options, the office port, mirrored records,
// a second interface in the pcapng, and a capture that begins inside a fault (--start-in
// fault:RULE). The bus's frames stay the bus's: each shape is compared with the plain run.
#include "ncservo/sim/capture_shapes.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/base/byte_reader.hpp"
#include "ncservo/base/little_endian.hpp"
#include "ncservo/capture/capture_writer.hpp"
#include "ncservo/protocol/pdo.hpp"
#include "ncservo/sim/simulator.hpp"
#include "ncservo/wire/ecat_wire.hpp"
#include "ncservo/wire/ethercat.hpp"
#include "row_name.hpp"
#include "status_text.hpp"

namespace ncservo::sim {
namespace {

using test::Bytes;

// --- --capture-stamps ---

struct StampsTextRow {
  const char* name;
  const char* text;
  std::optional<StampShape> shape;  // none: an error
  std::int64_t length_ns = 0;
  const char* error = "";  // the exact message
};
class ParseCaptureStamps : public ::testing::TestWithParam<StampsTextRow> {};

TEST_P(ParseCaptureStamps, Rows) {
  const StampsTextRow& row = GetParam();
  const Result<StampShaping> stamps = parseCaptureStamps(row.text);
  if (!row.shape) {
    ASSERT_FALSE(stamps.has_value());
    EXPECT_EQ(stamps.error().text(), row.error);
    return;
  }
  ASSERT_TRUE(stamps.has_value()) << stamps.error().text();
  EXPECT_EQ(stamps->shape, *row.shape);
  EXPECT_EQ(stamps->length_ns, row.length_ns);
  EXPECT_EQ(stamps->text, row.text);
}

constexpr const char* kExpectedShape =
    ": expected SHAPE:LENGTH, SHAPE bunched, quantised or late and LENGTH in us or ms, e.g. "
    "bunched:4ms";
INSTANTIATE_TEST_SUITE_P(
    Rows, ParseCaptureStamps,
    ::testing::Values(
        StampsTextRow{"bunched_4ms", "bunched:4ms", StampShape::Bunched, 4 * kMs},
        StampsTextRow{"bunched_least", "bunched:100us", StampShape::Bunched, 100 * kUs},
        StampsTextRow{"bunched_most", "bunched:100ms", StampShape::Bunched, 100 * kMs},
        StampsTextRow{"quantised_1ms", "quantised:1ms", StampShape::Quantised, kMs},
        StampsTextRow{"quantised_half_ms", "quantised:0.5ms", StampShape::Quantised, 500 * kUs},
        StampsTextRow{"quantised_1us", "quantised:1us", StampShape::Quantised, kUs},
        StampsTextRow{"late_400us", "late:400us", StampShape::Late, 400 * kUs},
        StampsTextRow{"late_10ms", "late:10ms", StampShape::Late, 10 * kMs},
        StampsTextRow{"no_colon", "bunched", std::nullopt, 0,
                      "--capture-stamps bunched: expected SHAPE:LENGTH, SHAPE bunched, quantised "
                      "or late and LENGTH in us or ms, e.g. bunched:4ms"},
        StampsTextRow{"unknown_shape", "jumbled:4ms", std::nullopt, 0,
                      "--capture-stamps jumbled:4ms: no shape 'jumbled' (bunched, quantised or "
                      "late)"},
        StampsTextRow{"no_unit", "late:400", std::nullopt, 0,
                      "--capture-stamps late:400: expected SHAPE:LENGTH, SHAPE bunched, "
                      "quantised or late and LENGTH in us or ms, e.g. bunched:4ms"},
        StampsTextRow{"seconds", "bunched:4s", std::nullopt, 0,
                      "--capture-stamps bunched:4s: expected SHAPE:LENGTH, SHAPE bunched, "
                      "quantised or late and LENGTH in us or ms, e.g. bunched:4ms"},
        StampsTextRow{"nanoseconds", "quantised:1.5us", std::nullopt, 0,
                      "--capture-stamps quantised:1.5us: expected SHAPE:LENGTH, SHAPE bunched, "
                      "quantised or late and LENGTH in us or ms, e.g. bunched:4ms"},
        StampsTextRow{"negative", "late:-4us", std::nullopt, 0,
                      "--capture-stamps late:-4us: expected SHAPE:LENGTH, SHAPE bunched, "
                      "quantised or late and LENGTH in us or ms, e.g. bunched:4ms"},
        StampsTextRow{"burst_too_short", "bunched:50us", std::nullopt, 0,
                      "--capture-stamps bunched:50us: a burst window from 100 us to 100 ms"},
        StampsTextRow{"burst_too_long", "bunched:101ms", std::nullopt, 0,
                      "--capture-stamps bunched:101ms: a burst window from 100 us to 100 ms"},
        StampsTextRow{"quantum_zero", "quantised:0us", std::nullopt, 0,
                      "--capture-stamps quantised:0us: a quantum from 1 us to 100 ms"},
        StampsTextRow{"late_too_late", "late:11ms", std::nullopt, 0,
                      "--capture-stamps late:11ms: the most a stamp is late from 1 us to 10 ms"}),
    test::rowName<StampsTextRow>);

// --- the clock ---

constexpr std::int64_t kT0 = 1'767'225'600 * kSecond;  // a whole second, as the simulator's epoch

// A record the clock stamps (its time on the bus), or the mirrored copy of the one before.
struct Passing {
  std::int64_t passed_ns;  // from kT0; ignored for a copy
  bool copy = false;
};
struct ClockRow {
  const char* name;
  const char* stamps;  // --capture-stamps text, "" for the bus's own times
  std::vector<Passing> records;
  std::vector<std::int64_t> expected;  // each record's stamp, from kT0
};
class CaptureClockRows : public ::testing::TestWithParam<ClockRow> {};

TEST_P(CaptureClockRows, StampsInCaptureOrder) {
  const ClockRow& row = GetParam();
  StampShaping stamps;
  if (*row.stamps != '\0') {
    const Result<StampShaping> parsed = parseCaptureStamps(row.stamps);
    ASSERT_TRUE(parsed.has_value()) << parsed.error().text();
    stamps = *parsed;
  }
  CaptureClock clock(stamps, 1);
  ASSERT_EQ(row.records.size(), row.expected.size());
  std::int64_t last = 0;
  for (std::size_t i = 0; i < row.records.size(); ++i) {
    const Passing& p = row.records[i];
    last = p.copy ? clock.duplicate(last) : clock.stamp(kT0 + p.passed_ns);
    EXPECT_EQ(last - kT0, row.expected[i]) << "record " << i + 1;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Rows, CaptureClockRows,
    ::testing::Values(
        ClockRow{"exact", "", {{0}, {3 * kUs}, {kMs}}, {0, 3 * kUs, kMs}},
        ClockRow{"exact_copies_1us_later",
                 "",
                 {{0}, {0, true}, {3 * kUs}, {0, true}},
                 {0, kUs, 3 * kUs, 4 * kUs}},
        // a 4 ms window: its records at its end, 2 us apart; the next window's at its end
        ClockRow{"bunched_4ms",
                 "bunched:4ms",
                 {{0}, {3 * kUs}, {kMs}, {3999 * kUs}, {4 * kMs}, {5 * kMs}},
                 {4 * kMs, 4 * kMs + 2 * kUs, 4 * kMs + 4 * kUs, 4 * kMs + 6 * kUs, 8 * kMs,
                  8 * kMs + 2 * kUs}},
        ClockRow{"bunched_copies_between",
                 "bunched:4ms",
                 {{kMs}, {0, true}, {2 * kMs}, {0, true}},
                 {4 * kMs, 4 * kMs + kUs, 4 * kMs + 2 * kUs, 4 * kMs + 3 * kUs}},
        ClockRow{"quantised_1ms",
                 "quantised:1ms",
                 {{0}, {250 * kUs}, {999 * kUs}, {kMs}, {1750 * kUs}},
                 {0, 0, 0, kMs, kMs}},
        ClockRow{"quantised_copies_same_stamp",
                 "quantised:1ms",
                 {{1250 * kUs}, {0, true}, {1500 * kUs}, {0, true}},
                 {kMs, kMs, kMs, kMs}},
        // never before the stamp before: a record that passed earlier than the last stamp
        ClockRow{"never_back", "", {{5 * kUs}, {3 * kUs}}, {5 * kUs, 5 * kUs}}),
    test::rowName<ClockRow>);

TEST(CaptureClockLate, WithinTheLengthNeverBackAndFromTheSeed) {
  const Result<StampShaping> stamps = parseCaptureStamps("late:400us");
  ASSERT_TRUE(stamps.has_value());
  auto run = [&](std::uint64_t seed) {
    CaptureClock clock(*stamps, seed);
    std::vector<std::int64_t> out;
    for (int k = 0; k < 2000; ++k) out.push_back(clock.stamp(kT0 + k * 125 * kUs) - kT0);
    return out;
  };
  const std::vector<std::int64_t> stamped = run(1);
  std::int64_t most_late = 0;
  for (std::size_t k = 0; k < stamped.size(); ++k) {
    const std::int64_t passed = static_cast<std::int64_t>(k) * 125 * kUs;
    EXPECT_GE(stamped[k], passed) << k;
    EXPECT_EQ(stamped[k] % kUs, 0) << "whole microseconds, as a pcap keeps them";
    if (k > 0) {
      EXPECT_GE(stamped[k], stamped[k - 1]) << k;
    }
    // late by the draw, or held back to the stamp before
    EXPECT_TRUE(stamped[k] <= passed + 400 * kUs || (k > 0 && stamped[k] == stamped[k - 1])) << k;
    most_late = std::max(most_late, stamped[k] - passed);
  }
  EXPECT_GT(most_late, 300 * kUs) << "the draws spread over the length";
  EXPECT_EQ(run(1), stamped);
  EXPECT_NE(run(2), stamped);
}

// --- the office port ---

TEST(OfficePort, CookedArpAndUdpAFewHundredASecond) {
  OfficePort port(7);
  port.start(kT0);
  std::int64_t last = kT0;
  int arp = 0, udp = 0;
  for (int i = 0; i < 1000; ++i) {
    SCOPED_TRACE("record " + std::to_string(i + 1));
    const std::int64_t gap = port.nextAt() - last;
    EXPECT_GE(gap, 500 * kUs);
    EXPECT_LE(gap, 7 * kMs);
    last = port.nextAt();
    const std::vector<std::uint8_t>& b = port.nextBytes();
    ASSERT_GE(b.size(), ecat::kSllHeaderSize + 28);
    EXPECT_EQ((b[2] << 8) | b[3], 1) << "ARPHRD_ETHER";
    EXPECT_EQ((b[4] << 8) | b[5], 6) << "a MAC";
    const int protocol = (b[14] << 8) | b[15];
    if (protocol == 0x0806) {
      ++arp;
      EXPECT_EQ(b.size(), ecat::kSllHeaderSize + 28);
      EXPECT_EQ((b[0] << 8) | b[1], 1) << "broadcast";
    } else {
      ASSERT_EQ(protocol, ecat::kEtherTypeIpv4);
      ++udp;
      const std::uint8_t* ip = &b[ecat::kSllHeaderSize];
      EXPECT_EQ(ip[0], 0x45);
      EXPECT_EQ(ip[9], ecat::kIpProtoUdp);
      EXPECT_EQ((ip[2] << 8) | ip[3], b.size() - ecat::kSllHeaderSize) << "IPv4 total length";
      std::uint32_t sum = 0;  // a header with its checksum sums to 0xFFFF (RFC 1071)
      for (int k = 0; k < 20; k += 2) sum += (ip[k] << 8) | ip[k + 1];
      while (sum > 0xFFFF) sum = (sum & 0xFFFF) + (sum >> 16);
      EXPECT_EQ(sum, 0xFFFFu);
    }
    port.advance();
  }
  const double per_second = 1000.0 / (static_cast<double>(last - kT0) * 1e-9);
  EXPECT_GT(per_second, 150);
  EXPECT_LT(per_second, 600);
  EXPECT_GT(arp, 100);
  EXPECT_GT(udp, 500);
}

// --- the options ---

struct ResolveRow {
  const char* name;
  std::function<void(SimOptions&)> change;
  const char* error;  // a part of the message; "" = resolves
};
class CaptureShapeOptions : public ::testing::TestWithParam<ResolveRow> {};

FaultRequest fault(const char* text) {
  const Result<FaultRequest> f = parseFault(text);
  EXPECT_TRUE(f.has_value()) << f.error().text();
  return f.value_or(FaultRequest{});
}
void startInFault(SimOptions& o, const char* text) {
  const Result<MidStartRequest> start = parseMidStart(text);
  ASSERT_TRUE(start.has_value()) << start.error().text();
  o.mid_start = start->start;
  o.mid_start_fault = start->fault;
}

TEST_P(CaptureShapeOptions, Rows) {
  const ResolveRow& row = GetParam();
  SimOptions o;
  row.change(o);
  const std::string error = test::statusText(resolveOptions(o));
  if (std::string(row.error).empty()) {
    EXPECT_EQ(error, "") << row.name;
  } else {
    EXPECT_NE(error.find(row.error), std::string::npos) << row.name << ": " << error;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Rows, CaptureShapeOptions,
    ::testing::Values(
        ResolveRow{"second_interface_pcap", [](SimOptions& o) { o.second_interface = true; },
                   "--second-interface: a pcap holds one interface; write a pcapng (--format "
                   "pcapng or a .pcapng file)"},
        ResolveRow{"second_interface_pcapng",
                   [](SimOptions& o) {
                     o.second_interface = true;
                     o.writes_pcapng = true;
                   },
                   ""},
        ResolveRow{"duplicates_pcap", [](SimOptions& o) { o.duplicate_records = true; }, ""},
        ResolveRow{"start_in_fault_se003", [](SimOptions& o) { startInFault(o, "fault:SE-003"); },
                   ""},
        ResolveRow{"start_in_fault_given",
                   [](SimOptions& o) {
                     startInFault(o, "fault:FLT-001");
                     o.faults = {fault("SE-001@1.2:0"), fault("FLT-001@0.8:2")};
                   },
                   ""},
        ResolveRow{"start_in_fault_other_before",
                   [](SimOptions& o) {
                     startInFault(o, "fault:SE-003");
                     o.faults = {fault("SE-001@0.85:0"), fault("SE-003@0.8:1")};
                   },
                   "--fault SE-001@0.85:0: 0.85 s is outside the quiet part of the run (0.9 s to "
                   "1.34 s)"},
        ResolveRow{"start_in_fault_out_of_quiet",
                   [](SimOptions& o) {
                     startInFault(o, "fault:SE-003");
                     o.faults = {fault("SE-003@2")};
                   },
                   "--fault SE-003@2: 2 s is outside the quiet part of the run"},
        ResolveRow{"start_in_fault_soak",
                   [](SimOptions& o) {
                     o.scenario = Scenario::Soak;
                     startInFault(o, "fault:SE-003");
                   },
                   "--start-in: a commissioning run only, without --idle"},
        ResolveRow{"start_in_fault_startup_fault",
                   [](SimOptions& o) {
                     startInFault(o, "fault:SE-003");
                     o.faults = {fault("ESM-002")};
                   },
                   "--fault ESM-002: ESM-002 happens in the start-up, which --start-in cuts "
                   "away"}),
    test::rowName<ResolveRow>);

struct MidStartRow {
  const char* name;
  const char* text;
  MidStart start;
  std::optional<RuleId> fault;
  const char* error = "";  // the exact message; "" = parses
};
class ParseMidStart : public ::testing::TestWithParam<MidStartRow> {};

TEST_P(ParseMidStart, Rows) {
  const MidStartRow& row = GetParam();
  const Result<MidStartRequest> start = parseMidStart(row.text);
  if (*row.error != '\0') {
    ASSERT_FALSE(start.has_value());
    EXPECT_EQ(start.error().text(), row.error);
    return;
  }
  ASSERT_TRUE(start.has_value()) << start.error().text();
  EXPECT_EQ(start->start, row.start);
  EXPECT_EQ(start->fault, row.fault);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, ParseMidStart,
    ::testing::Values(
        MidStartRow{"homing", "homing", MidStart::Homing, std::nullopt},
        MidStartRow{"fault", "fault", MidStart::Fault, std::nullopt},
        MidStartRow{"in_se003", "fault:SE-003", MidStart::InFault, RuleId::Se003},
        MidStartRow{"in_flt001_lower_case", "fault:flt-001", MidStart::InFault, RuleId::Flt001},
        MidStartRow{"nowhere", "nowhere", MidStart::None, std::nullopt,
                    "--start-in nowhere: one of homing, fault, error-clear, or fault:RULE with "
                    "RULE one of SE-003, FLT-001"},
        MidStartRow{"no_such_rule", "fault:XX-001", MidStart::None, std::nullopt,
                    "--start-in fault:XX-001: no rule 'XX-001' (see `ncservo rules`)"},
        MidStartRow{"a_moment", "fault:SE-002", MidStart::None, std::nullopt,
                    "--start-in fault:SE-002: SE-002's fault has no standing condition to begin "
                    "inside; one of SE-003, FLT-001"}),
    test::rowName<MidStartRow>);

// --- what the simulator writes ---

struct Record {
  std::int64_t time_ns;
  Bytes bytes;
  bool returned;
  std::uint32_t interface_id;
};

std::vector<Record> simulate(SimOptions o) {
  EXPECT_EQ(test::statusText(resolveOptions(o)), "");
  std::vector<Record> records;
  Simulator simulator(o);
  const auto count = simulator.run([&](const SimFrame& f) {
    records.push_back({f.time_ns, Bytes(f.data, f.data + f.size), f.returned, f.interface_id});
    return true;
  });
  EXPECT_TRUE(count.has_value());
  if (count) {
    EXPECT_EQ(*count, records.size());
  }
  return records;
}
std::vector<Record> onInterface(const std::vector<Record>& records, std::uint32_t interface) {
  std::vector<Record> kept;
  std::copy_if(records.begin(), records.end(), std::back_inserter(kept),
               [&](const Record& r) { return r.interface_id == interface; });
  return kept;
}
std::uint64_t fnv(const std::vector<Record>& records) {
  std::uint64_t h = 0xCBF29CE484222325ULL;
  auto mix = [&](std::uint8_t byte) { h = (h ^ byte) * 0x100000001B3ULL; };
  for (const Record& r : records) {
    for (int i = 0; i < 8; ++i) mix(static_cast<std::uint8_t>(r.time_ns >> (8 * i)));
    for (std::uint8_t b : r.bytes) mix(b);
  }
  return h;
}
SimOptions plainRun() {
  SimOptions o;
  o.axes = 2;
  o.duration_s = 1.0;
  o.jitter_us = 20;  // times that are not round numbers
  return o;
}

// Each shape of the stamps: the same frames in the same order with the same bytes (the DC
// system time they carry included), each stamped as the shape says from the bus's time.
struct StampRunRow {
  const char* name;
  const char* stamps;
  std::function<void(std::int64_t passed, std::int64_t stamp, std::int64_t length)> check;
};
class StampedRun : public ::testing::TestWithParam<StampRunRow> {};

TEST_P(StampedRun, TheBusFramesStampedAsTheShapeSays) {
  const StampRunRow& row = GetParam();
  const std::vector<Record> plain = simulate(plainRun());
  SimOptions o = plainRun();
  o.capture_stamps = *parseCaptureStamps(row.stamps);
  const std::vector<Record> stamped = simulate(o);
  ASSERT_EQ(stamped.size(), plain.size());
  for (std::size_t k = 0; k < plain.size(); ++k) {
    SCOPED_TRACE("record " + std::to_string(k + 1));
    ASSERT_EQ(stamped[k].bytes, plain[k].bytes);
    if (k > 0) {
      ASSERT_GE(stamped[k].time_ns, stamped[k - 1].time_ns) << "never back";
    }
    row.check(plain[k].time_ns, stamped[k].time_ns, o.capture_stamps.length_ns);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Rows, StampedRun,
    ::testing::Values(StampRunRow{"bunched_4ms", "bunched:4ms",
                                  [](std::int64_t passed, std::int64_t stamp, std::int64_t length) {
                                    const std::int64_t end = (passed / length + 1) * length;
                                    EXPECT_GE(stamp, end) << "at the end of its window";
                                    EXPECT_LT(stamp, end + 100 * kUs) << "a burst a few us apart";
                                    EXPECT_EQ((stamp - end) % kBurstSpacingNs, 0);
                                  }},
                      StampRunRow{"quantised_1ms", "quantised:1ms",
                                  [](std::int64_t passed, std::int64_t stamp, std::int64_t length) {
                                    EXPECT_EQ(stamp, passed / length * length);
                                  }},
                      StampRunRow{"late_400us", "late:400us",
                                  [](std::int64_t passed, std::int64_t stamp, std::int64_t length) {
                                    EXPECT_GE(stamp, passed);
                                    // held back to the stamp before by at most a cycle (1 ms)
                                    EXPECT_LE(stamp, passed + length + kMs);
                                  }}),
    test::rowName<StampRunRow>);

TEST(MirroredRun, EveryRecordTwiceTheCopyRightAfter) {
  for (const char* stamps : {"", "quantised:1ms", "bunched:2ms", "late:300us"}) {
    SCOPED_TRACE(stamps);
    SimOptions o = plainRun();
    if (*stamps != '\0') o.capture_stamps = *parseCaptureStamps(stamps);
    const std::vector<Record> single = simulate(o);
    o.duplicate_records = true;
    const std::vector<Record> mirrored = simulate(o);
    ASSERT_EQ(mirrored.size(), 2 * single.size());
    const bool quantised = o.capture_stamps.shape == StampShape::Quantised;
    for (std::size_t k = 0; k < single.size(); ++k) {
      const Record& original = mirrored[2 * k];
      const Record& copy = mirrored[2 * k + 1];
      ASSERT_EQ(original.bytes, single[k].bytes) << "record " << 2 * k + 1;
      ASSERT_EQ(copy.bytes, original.bytes) << "record " << 2 * k + 2;
      EXPECT_EQ(copy.returned, original.returned);
      EXPECT_EQ(copy.time_ns - original.time_ns, quantised ? 0 : kDuplicateLagNs)
          << "record " << 2 * k + 2;
      if (k > 0) {
        EXPECT_GE(original.time_ns, mirrored[2 * k - 1].time_ns) << "never back";
      }
    }
  }
}

TEST(SecondInterface, OfficeRecordsBetweenTheBusFramesByTime) {
  const std::vector<Record> plain = simulate(plainRun());
  SimOptions o = plainRun();
  o.second_interface = true;
  o.writes_pcapng = true;
  const std::vector<Record> both = simulate(o);
  const std::vector<Record> bus = onInterface(both, 0);
  const std::vector<Record> office = onInterface(both, 1);
  ASSERT_EQ(bus.size(), plain.size());
  for (std::size_t k = 0; k < bus.size(); ++k) {
    ASSERT_EQ(bus[k].bytes, plain[k].bytes) << "bus frame " << k + 1;
    ASSERT_EQ(bus[k].time_ns, plain[k].time_ns) << "bus frame " << k + 1;
  }
  EXPECT_EQ(bus.size() + office.size(), both.size());
  EXPECT_GT(office.size(), 150U) << "a few hundred a second";
  EXPECT_LT(office.size(), 600U);
  for (std::size_t k = 1; k < both.size(); ++k) {
    ASSERT_GE(both[k].time_ns, both[k - 1].time_ns) << "interleaved by time, record " << k + 1;
  }
  EXPECT_GT(office.front().time_ns, bus.front().time_ns) << "the port starts with the capture";
  EXPECT_EQ(fnv(office), fnv(onInterface(simulate(o), 1))) << "drawn from the seed";
}

// The incidents' truth names the capture's records: the original of a mirrored pair, counted
// with the office port's records.
TEST(IncidentTruthRecords, TheCapturesRecordsNotTheBussFrames) {
  SimOptions o;
  o.scenario = Scenario::Incidents;
  o.duration_s = 6;
  o.cycle_us = 5000;
  SimOptions plain_options = o;
  ASSERT_EQ(test::statusText(resolveOptions(plain_options)), "");
  Simulator plain_simulator(plain_options);
  std::vector<Bytes> plain;
  ASSERT_TRUE(plain_simulator.run([&](const SimFrame& f) {
    plain.emplace_back(f.data, f.data + f.size);
    return true;
  }));
  const Result<std::vector<IncidentTruth>> plain_truth = plain_simulator.incidents();
  ASSERT_TRUE(plain_truth.has_value()) << plain_truth.error().text();

  o.duplicate_records = true;
  o.second_interface = true;
  o.writes_pcapng = true;
  o.capture_stamps = *parseCaptureStamps("late:300us");
  ASSERT_EQ(test::statusText(resolveOptions(o)), "");
  Simulator shaped_simulator(o);
  std::vector<Record> shaped;
  ASSERT_TRUE(shaped_simulator.run([&](const SimFrame& f) {
    shaped.push_back({f.time_ns, Bytes(f.data, f.data + f.size), f.returned, f.interface_id});
    return true;
  }));
  const Result<std::vector<IncidentTruth>> truth = shaped_simulator.incidents();
  ASSERT_TRUE(truth.has_value()) << truth.error().text();
  ASSERT_EQ(truth->size(), plain_truth->size());
  for (std::size_t i = 0; i < truth->size(); ++i) {
    const IncidentTruth& was = (*plain_truth)[i];
    const IncidentTruth& is = (*truth)[i];
    SCOPED_TRACE(is.kind + " at record " + std::to_string(is.frame));
    EXPECT_EQ(is.kind, was.kind);
    EXPECT_EQ(is.axis, was.axis);
    ASSERT_LE(is.frame, shaped.size());
    const Record& record = shaped[is.frame - 1];
    EXPECT_EQ(record.interface_id, 0U);
    EXPECT_EQ(record.bytes, plain[was.frame - 1]);
    EXPECT_NE(shaped[is.frame - 2].bytes, record.bytes) << "the original, not its copy";
  }
}

// --- the pcapng of two interfaces ---

// The pcapng's IDBs' link types and each EPB's interface, read from the file's blocks.
struct PcapngBlocks {
  std::vector<int> link_types;
  std::vector<std::uint32_t> record_interfaces;
};
PcapngBlocks readBlocks(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const Bytes file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  PcapngBlocks blocks;
  for (std::size_t at = 0; at + 12 <= file.size();) {
    const auto type = static_cast<std::uint32_t>(loadLe<4>(&file[at]));
    const auto length = static_cast<std::size_t>(loadLe<4>(&file[at + 4]));
    if (length < 12) break;
    if (type == 1) blocks.link_types.push_back(static_cast<int>(loadLe<2>(&file[at + 8])));
    if (type == 6) {
      blocks.record_interfaces.push_back(static_cast<std::uint32_t>(loadLe<4>(&file[at + 8])));
    }
    at += length;
  }
  return blocks;
}

TEST(CaptureWriterInterfaces, EachRecordOnItsInterface) {
  char path[] = "/tmp/ncservo_interfaces_XXXXXX";
  const int fd = mkstemp(path);
  ASSERT_GE(fd, 0);
  close(fd);
  auto writer = CaptureWriter::open(path, CaptureFormat::Pcapng, Compression::None,
                                    {{.dlt = ecat::kDltEthernet}, {.dlt = ecat::kDltLinuxSll}});
  ASSERT_TRUE(writer) << writer.error().text();
  const Bytes bytes(60, 0x11);
  for (std::uint32_t interface : {0U, 1U, 1U, 0U}) {
    ASSERT_TRUE((*writer)->write(PacketRecord{.time_ns = kT0,
                                              .data = bytes.data(),
                                              .captured = bytes.size(),
                                              .original = bytes.size(),
                                              .interface_id = interface}));
  }
  EXPECT_FALSE((*writer)->write(PacketRecord{.time_ns = kT0,
                                             .data = bytes.data(),
                                             .captured = bytes.size(),
                                             .original = bytes.size(),
                                             .interface_id = 2}))
      << "no third interface";
  ASSERT_TRUE((*writer)->close());
  const PcapngBlocks blocks = readBlocks(path);
  EXPECT_EQ(blocks.link_types, (std::vector<int>{1, 113}));
  EXPECT_EQ(blocks.record_interfaces, (std::vector<std::uint32_t>{0, 1, 1, 0}));
  std::remove(path);
}

TEST(CaptureWriterInterfaces, APcapRefusesASecondInterface) {
  auto writer =
      CaptureWriter::open("/tmp/never-written.pcap", CaptureFormat::Pcap, Compression::None,
                          {{.dlt = ecat::kDltEthernet}, {.dlt = ecat::kDltLinuxSll}});
  ASSERT_FALSE(writer);
  EXPECT_EQ(writer.error().text(),
            "/tmp/never-written.pcap: a pcap holds one Ethernet interface: write a pcapng");
}

// --- a capture that begins inside a fault ---

// Axis `axis`'s control and status words in a returned copy (its LRW's outputs and inputs).
std::optional<std::pair<std::uint32_t, std::uint32_t>> scwAndSsw(const Bytes& bytes,
                                                                 const AxisConfig& axis) {
  EcatFrame frame;
  walkPacket(LinkType::Ethernet, ByteReader(bytes.data(), bytes.size()), frame);
  PdoValues values;
  for (std::size_t d = 0; d < frame.count; ++d) {
    const Datagram& dg = frame.datagrams[d];
    if (dg.command != ecat::kLrw) continue;
    const ByteReader reader(bytes.data(), bytes.size());
    for (auto [address, pdo] : {std::pair{*axis.outputs, Pdo::Rx}, {*axis.inputs, Pdo::Tx}}) {
      if (address >= dg.address && address - dg.address + sizeOfPdo(pdo) <= dg.length) {
        readPdo(pdo, reader, dg.data_offset + (address - dg.address), values);
      }
    }
  }
  if (!values.has_rx || !values.has_tx) return std::nullopt;
  return std::pair{values.scw(), values.ssw()};
}

struct InFaultRow {
  const char* name;
  const char* start_in;
  bool enable_requested;  // SE 0x2 in the first cycles (FLT-001) or not (SE-003)
};
class StartInFault : public ::testing::TestWithParam<InFaultRow> {};

TEST_P(StartInFault, FirstCyclesHoldServoEnAsTheFaultHasIt) {
  const InFaultRow& row = GetParam();
  SimOptions o;
  startInFault(o, row.start_in);
  o.faults = {fault((std::string(row.start_in).substr(6) + "@1.0:2").c_str())};
  ASSERT_EQ(test::statusText(resolveOptions(o)), "");
  const AxisConfig axis = Simulator(o).layout()[2];
  const std::vector<Record> records = simulate(o);
  ASSERT_GT(records.size(), 100U);
  const std::int64_t first = records.front().time_ns - 1'767'225'600 * kSecond;
  EXPECT_GE(first, 1000 * kMs) << "nothing before the fault";
  EXPECT_LE(first, 1002 * kMs);
  int returned = 0;
  for (const Record& r : records) {
    if (!r.returned) continue;
    if (++returned > 10) break;
    const auto words = scwAndSsw(r.bytes, axis);
    ASSERT_TRUE(words.has_value()) << "returned copy " << returned;
    const std::uint32_t se = words->first & bits::kSe;
    EXPECT_EQ(se == bits::kSeEnable, row.enable_requested) << "returned copy " << returned;
    EXPECT_NE(words->second & bits::kServoEn, 0U) << "returned copy " << returned;
  }
}

INSTANTIATE_TEST_SUITE_P(Rows, StartInFault,
                         ::testing::Values(InFaultRow{"se003", "fault:SE-003", false},
                                           InFaultRow{"flt001", "fault:FLT-001", true}),
                         test::rowName<InFaultRow>);

}  // namespace
}  // namespace ncservo::sim
