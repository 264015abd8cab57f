// Distributed clocks (dc_clock.hpp, docs/timing.md "Distributed clocks"): 0x092C's sign, the
// settle logic, the drift fit on synthetic clocks, and which reads count, on frames built byte by
// byte.
#include "ncservo/model/dc_clock.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "frame_builder.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

using test::Bytes;
using test::Dg;
using test::FrameBuilder;
using test::physical;

constexpr std::uint16_t kStation = 0x1001;
constexpr std::uint16_t kOtherStation = 0x1002;

Bytes le(std::uint64_t value, std::size_t size) {
  Bytes out;
  test::putLe(out, value, size);
  return out;
}
std::uint16_t apAdp(std::uint16_t position) {
  return static_cast<std::uint16_t>((0x10000u - position) & 0xFFFFu);
}

// Feeds master copies and returned copies to one DcClock, numbering frames from 1.
struct Harness {
  explicit Harness(std::int64_t settled_ns = 100) : clock(settled_ns) {}
  DcClock clock;
  std::uint64_t frame = 0;

  void feed(const std::vector<Dg>& dgs, bool returned, bool paired, std::int64_t time_ns) {
    FrameBuilder builder;
    for (const Dg& dg : dgs) builder.add(dg);
    const Bytes bytes = builder.bytes();
    const test::Walked w = test::walk(bytes);
    clock.onFrame(*w.frame, w.reader(), returned, paired, ++frame, time_ns);
  }
  // A master's copy (data as sent, WKC 0) and its returned copy.
  void exchange(Dg dg, const Bytes& returned_data, std::int64_t time_ns) {
    Dg back = dg;
    back.data = returned_data;
    back.wkc = dg.wkc;
    dg.wkc = 0;
    // A write's master copy carries the data; a read's comes back filled.
    dg.data = ecat::writesSlaves(dg.cmd) ? returned_data : Bytes(returned_data.size(), 0);
    feed({dg}, false, false, time_ns);
    feed({back}, true, true, time_ns + 20'000);
  }
  void readTime(std::uint8_t cmd, std::uint16_t adp, std::uint64_t time, std::int64_t time_ns,
                std::size_t size = 8) {
    exchange(Dg{cmd, 0, physical(adp, ecat::kRegDcSystemTime), {}, 1}, le(time, size), time_ns);
  }
  void readDifference(std::uint16_t station, std::uint32_t raw, std::uint16_t wkc = 1) {
    exchange(Dg{ecat::kFprd, 0, physical(station, ecat::kRegDcSystemTimeDifference), {}, wkc},
             le(raw, 4), static_cast<std::int64_t>(frame) * 1'000'000);
  }
};

struct SignCase {
  std::string name;
  std::uint32_t raw;
  std::int64_t ns;
};
class DcSign : public ::testing::TestWithParam<SignCase> {};
TEST_P(DcSign, Decodes) {
  EXPECT_EQ(systemTimeDifferenceNs(GetParam().raw), GetParam().ns);
}
INSTANTIATE_TEST_SUITE_P(DcClock, DcSign,
                         ::testing::Values(SignCase{"zero", 0x00000000, 0},
                                           SignCase{"local ahead 253 ns", 0xFD, 253},
                                           SignCase{"local behind 12 ns", 0x8000000C, -12},
                                           SignCase{"negative zero", 0x80000000, 0},
                                           SignCase{"largest ahead", 0x7FFFFFFF, 0x7FFFFFFF},
                                           SignCase{"largest behind", 0xFFFFFFFF, -0x7FFFFFFF}),
                         test::rowName<SignCase>);

// One slave's 0x092C reads in order (raw values), then what the clock says of them.
struct SettleCase {
  std::string name;
  std::vector<std::uint32_t> reads;
  std::int64_t bound_ns;
  std::int64_t last_ns;
  std::int64_t max_abs_ns;
  std::optional<std::uint64_t> settled_read;  // 1-based index of the read that settled it
};
class DcSettle : public ::testing::TestWithParam<SettleCase> {};
TEST_P(DcSettle, FirstReadOfTheLastRunWithinTheBound) {
  const SettleCase& c = GetParam();
  Harness h(c.bound_ns);
  for (std::uint32_t raw : c.reads) h.readDifference(kStation, raw);
  const std::vector<DcStation> stations = h.clock.stations();
  ASSERT_EQ(stations.size(), 1u);
  const DcStation& s = stations[0];
  EXPECT_EQ(s.slave.station, kStation);
  EXPECT_FALSE(s.reference);
  EXPECT_EQ(s.difference_reads, c.reads.size());
  EXPECT_EQ(s.last_difference_ns, c.last_ns);
  EXPECT_EQ(s.max_abs_difference_ns, c.max_abs_ns);
  // Each read is a master copy (odd frame) and its returned copy (even frame): read k in frame 2k.
  const std::optional<std::uint64_t> frame =
      c.settled_read ? std::optional<std::uint64_t>(2 * *c.settled_read) : std::nullopt;
  EXPECT_EQ(s.settled_frame, frame);
}
INSTANTIATE_TEST_SUITE_P(
    DcClock, DcSettle,
    ::testing::Values(
        SettleCase{"within from the start", {0x10, 0x8000000A, 0x05}, 100, 5, 16, 1},
        SettleCase{
            "settles after large ones", {0x80000370, 0x200, 0x8000001E, 0x3}, 100, 3, 880, 3},
        SettleCase{"bound is inclusive", {0x80000064, 0x64}, 100, 100, 100, 1},
        SettleCase{"leaves the bound again", {0x1, 0x2, 0x80000065, 0x3}, 100, 3, 101, 4},
        SettleCase{"never within", {0x1000, 0x80000800}, 100, -2048, 4096, std::nullopt},
        SettleCase{"last read outside", {0x1, 0x8000FFFF}, 100, -65535, 65535, std::nullopt},
        SettleCase{"a tighter bound", {0x30, 0x10, 0x8}, 10, 8, 48, 3}),
    test::rowName<SettleCase>);

// A reference clock `ppm` fast (or slow) against the frame timestamps, read every `period_ns`,
// with a step of `ppm_step` from the middle on.
struct DriftCase {
  std::string name;
  double ppm;
  double ppm_step;
  std::int64_t period_ns;
  int reads;
  std::size_t size;  // bytes read of 0x0910
  std::uint64_t start;
};
class DcDrift : public ::testing::TestWithParam<DriftCase> {};
TEST_P(DcDrift, FitsTheSyntheticClock) {
  const DriftCase& c = GetParam();
  Harness h;
  const std::int64_t t0 = 1'700'000'000'000'000'000;
  double clock = static_cast<double>(c.start);
  std::int64_t last = t0;
  for (int i = 0; i < c.reads; ++i) {
    const std::int64_t t = t0 + static_cast<std::int64_t>(i) * c.period_ns;
    const double ppm = i >= c.reads / 2 ? c.ppm + c.ppm_step : c.ppm;
    clock += static_cast<double>(t - last) * (1.0 + ppm * 1e-6);
    last = t;
    const auto value = static_cast<std::uint64_t>(clock);
    // The returned copy is timestamped 20 µs after its master copy (Harness::exchange).
    h.readTime(ecat::kFrmw, kStation, value, t - 20'000, c.size);
  }
  const std::vector<DcStation> stations = h.clock.stations();
  ASSERT_EQ(stations.size(), 1u);
  const DcStation& s = stations[0];
  EXPECT_TRUE(s.reference);
  EXPECT_EQ(s.time_reads, static_cast<std::uint64_t>(c.reads));
  ASSERT_TRUE(s.drift_ppm && s.first_half_ppm && s.second_half_ppm);
  // The halves are split at a block boundary near the middle: a step shows in each half's fit
  // within the share of its half that lies beyond the middle.
  const double tolerance = 0.01 + std::abs(c.ppm_step) * 0.3;
  EXPECT_NEAR(*s.drift_ppm, c.ppm + c.ppm_step / 2, tolerance);
  EXPECT_NEAR(*s.first_half_ppm, c.ppm, tolerance);
  EXPECT_NEAR(*s.second_half_ppm, c.ppm + c.ppm_step, tolerance);
}
INSTANTIATE_TEST_SUITE_P(
    DcClock, DcDrift,
    ::testing::Values(DriftCase{"exact clock", 0, 0, 1'000'000, 2000, 8, 1'000'000},
                      DriftCase{"fast 12.5 ppm", 12.5, 0, 1'000'000, 2000, 8, 5'000'000},
                      DriftCase{"slow 40 ppm", -40, 0, 500'000, 5000, 8, 0},
                      DriftCase{"a step from 0 to 20 ppm", 0, 20, 1'000'000, 4000, 8, 77},
                      DriftCase{"32-bit reads wrap", 3, 0, 1'000'000, 10'000, 4, 0xFFF00000},
                      DriftCase{"long capture, 10 ms cycle", -7.5, 0, 10'000'000, 20'000, 8,
                                1ull << 40}),
    test::rowName<DriftCase>);

// The slope's standard error, worked by hand: x 0..3, y 0, 1, 1, 2 give the line y = 0.4 + 0.6 x
// with residuals -0.4, 0.2, -0.4, 0.2... summing to 0.2 squared; SE = sqrt(0.2 / 2 / 5).
TEST(LineFitError, ByHand) {
  LineFit scattered;
  for (const auto& [x, y] : {std::pair{0.0, 0.0}, {1.0, 1.0}, {2.0, 1.0}, {3.0, 2.0}})
    scattered.add(x, y);
  ASSERT_TRUE(scattered.slopeStandardError());
  EXPECT_NEAR(*scattered.slope(), 0.6, 1e-12);
  EXPECT_NEAR(*scattered.slopeStandardError(), 0.1414213562, 1e-9);
  LineFit straight;
  for (const double x : {0.0, 1.0, 2.0, 5.0}) straight.add(x, 3.0 + 2.0 * x);
  EXPECT_NEAR(*straight.slopeStandardError(), 0.0, 1e-9);
  LineFit two;
  two.add(0, 0);
  two.add(1, 1);
  EXPECT_FALSE(two.slopeStandardError());  // a line through two points leaves nothing to scatter
}

// Stamps jittered by a PC (uniform, ±`jitter_ns`): the drift found lies within its uncertainty of
// the clock's, and the uncertainty grows with the jitter.
TEST(DcDriftUncertainty, CoversTheTruthAndGrowsWithTheJitter) {
  constexpr double kPpm = 37.0;
  std::optional<double> previous;
  for (const std::int64_t jitter_ns : {0LL, 20'000LL, 200'000LL}) {
    Harness h;
    std::uint64_t state = 12345;  // a fixed LCG: the same stamps on every run
    const std::int64_t t0 = 1'700'000'000'000'000'000;
    for (int i = 0; i < 4000; ++i) {
      const std::int64_t bus_ns = static_cast<std::int64_t>(i) * 1'000'000;
      state = state * 6364136223846793005ULL + 1442695040888963407ULL;
      const auto draw = static_cast<double>(state >> 11) / 9007199254740992.0;  // [0, 1)
      const auto stamp_jitter = static_cast<std::int64_t>((2 * draw - 1) * jitter_ns);
      const auto clock = static_cast<std::uint64_t>(1'000'000 + bus_ns * (1 + kPpm * 1e-6));
      h.readTime(ecat::kFrmw, kStation, clock, t0 + bus_ns + stamp_jitter);
    }
    const DcStation s = h.clock.stations().at(0);
    ASSERT_TRUE(s.drift_ppm && s.drift_uncertainty_ppm) << jitter_ns;
    EXPECT_LE(std::abs(*s.drift_ppm - kPpm), *s.drift_uncertainty_ppm + 1e-3) << jitter_ns;
    if (previous) {
      EXPECT_GT(*s.drift_uncertainty_ppm, *previous * 5) << jitter_ns;
    }
    previous = s.drift_uncertainty_ppm;
  }
}

// Which reads count: returned copies only, some slave answered, one slave addressed.
struct ReadCase {
  std::string name;
  std::uint8_t cmd;
  std::uint16_t adp;
  std::uint16_t wkc;
  bool counted;
  bool reference;
  std::optional<std::uint16_t> station;
  std::optional<std::uint16_t> position;
};
class DcReads : public ::testing::TestWithParam<ReadCase> {};
TEST_P(DcReads, CountedOrNot) {
  const ReadCase& c = GetParam();
  Harness h;
  for (int i = 0; i < 3; ++i) {
    h.exchange(Dg{c.cmd, 0, physical(c.adp, ecat::kRegDcSystemTime), {}, c.wkc},
               le(1'000'000 + static_cast<std::uint64_t>(i) * 1'000'000, 8), i * 1'000'000);
  }
  const std::vector<DcStation> stations = h.clock.stations();
  if (!c.counted) {
    EXPECT_TRUE(stations.empty());
    return;
  }
  ASSERT_EQ(stations.size(), 1u);
  EXPECT_EQ(stations[0].time_reads, 3u);
  EXPECT_EQ(stations[0].reference, c.reference);
  EXPECT_EQ(stations[0].slave.station, c.station);
  EXPECT_EQ(stations[0].slave.position, c.position);
}
INSTANTIATE_TEST_SUITE_P(
    DcClock, DcReads,
    ::testing::Values(
        ReadCase{"FRMW", ecat::kFrmw, kStation, 1, true, true, kStation, std::nullopt},
        ReadCase{"ARMW names the ring position", ecat::kArmw, apAdp(2), 3, true, true, std::nullopt,
                 2},
        ReadCase{"FPRD of one slave's time", ecat::kFprd, kOtherStation, 1, true, false,
                 kOtherStation, std::nullopt},
        ReadCase{"APRD", ecat::kAprd, apAdp(0), 1, true, false, std::nullopt, 0},
        ReadCase{"no slave answered", ecat::kFrmw, kStation, 0, false, false, {}, {}},
        ReadCase{"broadcast read names no slave", ecat::kBrd, 0, 3, false, false, {}, {}},
        ReadCase{"a write is no read", ecat::kFpwr, kStation, 1, false, false, {}, {}}),
    test::rowName<ReadCase>);

TEST(DcClock, StationAssignmentNamesTheRingPosition) {
  Harness h;
  h.exchange(Dg{ecat::kApwr, 0, physical(apAdp(1), ecat::kRegStationAddress), le(kStation, 2), 1},
             le(kStation, 2), 0);
  for (int i = 0; i < 3; ++i) {
    h.readTime(ecat::kArmw, apAdp(1), 5'000'000 + static_cast<std::uint64_t>(i) * 1'000'000,
               1'000'000 + i * 1'000'000);
  }
  const std::vector<DcStation> stations = h.clock.stations();
  ASSERT_EQ(stations.size(), 1u);
  EXPECT_EQ(stations[0].slave.station, kStation);
  EXPECT_EQ(stations[0].slave.position, 1);
}

// A segment start, or a new system time offset written to the slave, starts the fit again; the
// system time differences carry on.
struct RestartCase {
  std::string name;
  bool segment;
  std::optional<std::uint8_t> offset_write;  // command of a write of 0x0920
  std::uint16_t offset_adp;
  std::uint64_t reads_after;  // in the fit at the end
};
class DcRestart : public ::testing::TestWithParam<RestartCase> {};
TEST_P(DcRestart, FitStartsAgain) {
  const RestartCase& c = GetParam();
  Harness h;
  h.readDifference(kStation, 0x5);
  for (int i = 0; i < 4; ++i) {
    h.readTime(ecat::kFrmw, kStation, 1'000'000'000 + static_cast<std::uint64_t>(i) * 1'000'000,
               i * 1'000'000);
  }
  if (c.segment) h.clock.startSegment();
  if (c.offset_write) {
    h.exchange(Dg{*c.offset_write, 0, physical(c.offset_adp, ecat::kRegDcSystemTimeOffset), {}, 1},
               le(123'456'789, 8), 5'000'000);
  }
  for (int i = 0; i < 2; ++i) {
    h.readTime(ecat::kFrmw, kStation, 9'000'000'000 + static_cast<std::uint64_t>(i) * 1'000'000,
               10'000'000 + i * 1'000'000);
  }
  const std::vector<DcStation> stations = h.clock.stations();
  ASSERT_EQ(stations.size(), 1u);
  EXPECT_EQ(stations[0].time_reads, c.reads_after);
  EXPECT_EQ(stations[0].difference_reads, 1u);
  EXPECT_EQ(stations[0].last_difference_ns, 5);
  if (c.reads_after == 2) {
    EXPECT_NEAR(*stations[0].drift_ppm, 0.0, 1e-6);
  }
}
INSTANTIATE_TEST_SUITE_P(DcClock, DcRestart,
                         ::testing::Values(RestartCase{"no restart", false, std::nullopt, 0, 6},
                                           RestartCase{"segment start", true, std::nullopt, 0, 2},
                                           RestartCase{"offset written to the slave", false,
                                                       ecat::kFpwr, kStation, 2},
                                           RestartCase{"offset broadcast", false, ecat::kBwr, 0, 2},
                                           RestartCase{"offset written to another slave", false,
                                                       ecat::kFpwr, kOtherStation, 6}),
                         test::rowName<RestartCase>);

// Every cut of a frame: no read past the captured bytes (ASan), and a cut read is not taken.
TEST(DcClock, TruncatedFramesNeverReadPastTheEnd) {
  FrameBuilder builder;
  builder.add(Dg{ecat::kFprd, 0, physical(kStation, ecat::kRegDcSystemTime), Bytes(32, 0x11), 1});
  const Bytes bytes = builder.bytes();
  for (std::size_t size = 0; size < bytes.size(); ++size) {
    DcClock clock(100);
    const test::Walked w = test::walk(bytes, size);
    clock.onFrame(*w.frame, w.reader(), true, false, 1, 0);
    for (const DcStation& s : clock.stations()) EXPECT_LE(s.time_reads, 1u);
  }
}

// docs/protocol.md §8: a returned copy's auto-increment address is its master copy's, the frame
// just before, whatever registers that master copy reached (a master copy holds no read data
// itself).
TEST(DcClock, ReturnedCopyTakesThePositionOfTheMasterCopyJustBefore) {
  Harness h;
  h.feed({Dg{ecat::kAprd, 0, physical(apAdp(3), ecat::kRegDcSystemTime), Bytes(8, 0), 0}}, false,
         false, 1'000'000);
  h.feed({Dg{ecat::kAprd, 0, physical(apAdp(3) + 4, ecat::kRegDcSystemTime), le(5'000, 8), 1}},
         true, true, 1'020'000);
  const std::vector<DcStation> stations = h.clock.stations();
  ASSERT_EQ(stations.size(), 1u);
  EXPECT_EQ(stations[0].slave.position, std::optional<std::uint16_t>(3));
  EXPECT_EQ(stations[0].time_reads, 1u);
}

}  // namespace
}  // namespace ncservo
