// The capture's clock (docs/timing.md#the-clock): what the first cycles' stamps are fit for and
// the clock chosen from them; the clock stage's times on a simulated bus whose capture stamps
// were bunched, quantised or made late; duplicates dropped.
#include "ncservo/model/capture_clock.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "ncservo/pipeline/clock_stage.hpp"
#include "ncservo/sim/simulator.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

constexpr std::int64_t kUs = 1000;
constexpr std::int64_t kMs = 1000 * kUs;

// How the capturing PC stamped a frame the bus sent at `bus_ns` (the i-th, in order).
using Stamper = std::function<std::int64_t(std::size_t i, std::int64_t bus_ns)>;

std::int64_t bunched(std::int64_t bus_ns, std::int64_t burst_ns, std::size_t i) {
  return (bus_ns / burst_ns + 1) * burst_ns + static_cast<std::int64_t>(i % 64) * 2 * kUs;
}

Stamper steady() {
  return [](std::size_t, std::int64_t bus_ns) { return bus_ns; };
}
Stamper bunchedInto(std::int64_t burst_ns) {
  return [burst_ns](std::size_t i, std::int64_t bus_ns) { return bunched(bus_ns, burst_ns, i); };
}
Stamper quantisedTo(std::int64_t quantum_ns) {
  return
      [quantum_ns](std::size_t, std::int64_t bus_ns) { return bus_ns / quantum_ns * quantum_ns; };
}
// Late by a seeded 0..late_ns, never before the stamp before.
Stamper lateBy(std::int64_t late_ns) {
  auto random = std::make_shared<std::mt19937_64>(7);
  auto last = std::make_shared<std::int64_t>(0);
  return [=](std::size_t, std::int64_t bus_ns) {
    const std::int64_t late = static_cast<std::int64_t>((*random)() % (late_ns + 1));
    *last = std::max(*last, bus_ns + late);
    return *last;
  };
}

struct AssessRow {
  const char* name;
  std::int64_t cycle_ns;
  std::size_t cycles;
  Stamper stamper;
  bool bus_read;       // the frames read the reference clock
  bool bus_advances;   // ... and its time advances with the cycles
  bool probe = false;  // the probe timed the capture
  ClockSource source;
  bool quantised = false, bunched = false, late = false;
};

class AssessTest : public ::testing::TestWithParam<AssessRow> {};

TEST_P(AssessTest, ChoosesTheClock) {
  const AssessRow& row = GetParam();
  StampAssessor assessor;
  for (std::size_t i = 0; i < row.cycles; ++i) {
    const std::int64_t bus_ns = 1'000'000'000 + static_cast<std::int64_t>(i) * row.cycle_ns;
    std::optional<std::uint64_t> read;
    if (row.bus_read) read = row.bus_advances ? static_cast<std::uint64_t>(bus_ns) : 42;
    const std::int64_t stamp = row.stamper(i, bus_ns);
    assessor.add(stamp, read);
    if (read) assessor.addRead(stamp, *read);
  }
  std::optional<SystemTimeRead> reference;
  if (row.bus_read) reference = SystemTimeRead{0, true, ecat::kFrmw, 0x1001};
  const ClockChoice choice = chooseClock(row.probe, assessor, reference);
  EXPECT_EQ(clockSourceName(choice.source), std::string(clockSourceName(row.source))) << choice.why;
  EXPECT_EQ(choice.stamps.quantised, row.quantised) << choice.why;
  EXPECT_EQ(choice.stamps.bunched, row.bunched) << choice.why;
  EXPECT_EQ(choice.stamps.late, row.late) << choice.why;
  EXPECT_FALSE(choice.why.empty());
  if (choice.source == ClockSource::Cycles) {
    // The stamps' mean interval is the cycle, however they lie.
    EXPECT_NEAR(static_cast<double>(choice.cycle_ns), static_cast<double>(row.cycle_ns),
                row.cycle_ns * 0.02);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Stamps, AssessTest,
    ::testing::Values(AssessRow{"steady_with_bus", 250 * kUs, 600, steady(), true, true, false,
                                ClockSource::Capture},
                      AssessRow{"steady_without_bus", 1 * kMs, 600, steady(), false, false, false,
                                ClockSource::Capture},
                      AssessRow{"bunched_bus", 250 * kUs, 600, bunchedInto(4 * kMs), true, true,
                                false, ClockSource::Bus, false, true},
                      AssessRow{"bunched_no_bus", 250 * kUs, 600, bunchedInto(4 * kMs), false,
                                false, false, ClockSource::Cycles, false, true},
                      AssessRow{"bunched_bus_standing_still", 1 * kMs, 600, bunchedInto(8 * kMs),
                                true, false, false, ClockSource::Cycles, false, true},
                      AssessRow{"quantised_bus", 250 * kUs, 600, quantisedTo(1 * kMs), true, true,
                                false, ClockSource::Bus, true},
                      AssessRow{"quantised_no_bus", 250 * kUs, 600, quantisedTo(1 * kMs), false,
                                false, false, ClockSource::Cycles, true},
                      // A step finer than the cycle is no harm.
                      AssessRow{"fine_quantum", 1 * kMs, 600, quantisedTo(100 * kUs), true, true,
                                false, ClockSource::Capture},
                      AssessRow{"late_over_a_quarter", 250 * kUs, 600, lateBy(400 * kUs), true,
                                true, false, ClockSource::Bus, false, false, true},
                      AssessRow{"late_under_a_quarter", 1 * kMs, 600, lateBy(200 * kUs), true, true,
                                false, ClockSource::Capture},
                      AssessRow{"too_few", 1 * kMs, 5, bunchedInto(4 * kMs), true, true, false,
                                ClockSource::Capture},
                      AssessRow{"probe", 250 * kUs, 600, bunchedInto(4 * kMs), true, true, true,
                                ClockSource::Probe, false, true}),
    test::rowName<AssessRow>);

TEST(SystemTimeUnwrapper, ExtendsThirtyTwoBitReadsAcrossTheWrap) {
  SystemTimeUnwrapper unwrap;
  EXPECT_EQ(unwrap.extend({0xFFFF'FF00u, false, ecat::kFrmw, 0}), 0xFFFF'FF00u);
  EXPECT_EQ(unwrap.extend({0x0000'0100u, false, ecat::kFrmw, 0}), 0x1'0000'0100u);
  EXPECT_EQ(unwrap.extend({0x0000'0200u, false, ecat::kFrmw, 0}), 0x1'0000'0200u);
  // A 64-bit read is taken as it is.
  EXPECT_EQ(unwrap.extend({0x5'0000'0000u, true, ecat::kFrmw, 0}), 0x5'0000'0000u);
}

struct SimFrame {
  std::vector<std::uint8_t> bytes;
  std::int64_t time_ns;
};

// Two axes, one second at 250 us: each frame as the bus sent it.
const std::vector<SimFrame>& simulated() {
  static const std::vector<SimFrame> frames = [] {
    sim::SimOptions options;
    options.axes = 2;
    options.cycle_us = 250;
    options.duration_s = 1.0;
    EXPECT_TRUE(sim::resolveOptions(options));
    std::vector<SimFrame> out;
    sim::Simulator simulator(options);
    EXPECT_TRUE(simulator.run([&](const sim::SimFrame& f) {
      out.push_back({std::vector<std::uint8_t>(f.data, f.data + f.size), f.time_ns});
      return true;
    }));
    return out;
  }();
  return frames;
}

struct Passed {
  std::uint64_t number;
  std::int64_t time_ns;
};

// The frames through a clock stage, stamped by `stamper`, each given `copies` times.
void run(const Stamper& stamper, ClockStage& stage, int copies = 1) {
  std::uint64_t number = 0;
  EcatFrame frame;
  const std::vector<SimFrame>& frames = simulated();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const ByteReader bytes(frames[i].bytes.data(), frames[i].bytes.size());
    walkPacket(LinkType::Ethernet, bytes, frame);
    for (int c = 0; c < copies; ++c) {
      stage.onFrame(++number, stamper(i, frames[i].time_ns), LinkType::Ethernet, bytes, frame, true,
                    false);
    }
  }
  stage.finish();
}

struct BusRow {
  const char* name;
  Stamper stamper;
  ClockSource source;
};

class BusClockTest : public ::testing::TestWithParam<BusRow> {};

// Whatever the stamps, each frame's time on the chosen clock is the bus's, up to one offset:
// intervals between frames as the bus sent them (the returned copies a few microseconds early).
TEST_P(BusClockTest, TimesEveryCycleAsTheBusSentIt) {
  const BusRow& row = GetParam();
  std::vector<Passed> passed;
  ClockStage stage([&](std::uint64_t number, std::int64_t time_ns, LinkType, const ByteReader&,
                       const EcatFrame&, bool) {
    passed.push_back({number, time_ns});
  });
  run(row.stamper, stage);
  EXPECT_EQ(clockSourceName(stage.choice().source), std::string(clockSourceName(row.source)))
      << stage.choice().why;
  const std::vector<SimFrame>& frames = simulated();
  ASSERT_EQ(passed.size(), frames.size());
  std::int64_t worst = 0;
  std::optional<std::int64_t> offset;
  for (std::size_t i = 0; i < passed.size(); ++i) {
    ASSERT_EQ(passed[i].number, i + 1);
    if (i > 0) {
      EXPECT_GE(passed[i].time_ns, passed[i - 1].time_ns) << "frame " << i + 1;
    }
    // The cyclic frames, after the start-up: at most the ring's latency off.
    if (frames[i].time_ns - frames.front().time_ns < 300 * kMs) continue;
    const std::int64_t delta = passed[i].time_ns - frames[i].time_ns;
    if (!offset) offset = delta;
    worst = std::max(worst, std::abs(delta - *offset));
  }
  EXPECT_LE(worst, 10 * kUs) << row.name;
  EXPECT_EQ(stage.duplicates().count, 0u);
  EXPECT_EQ(stage.untimed(), 0u);
}

INSTANTIATE_TEST_SUITE_P(
    Stamps, BusClockTest,
    ::testing::Values(BusRow{"steady", steady(), ClockSource::Capture},
                      BusRow{"bunched_4ms", bunchedInto(4 * kMs), ClockSource::Bus},
                      BusRow{"quantised_1ms", quantisedTo(1 * kMs), ClockSource::Bus},
                      BusRow{"late_400us", lateBy(400 * kUs), ClockSource::Bus}),
    test::rowName<BusRow>);

struct EarlyRow {
  const char* name;
  Stamper stamper;
  std::size_t cycles;  // the cyclic frame's copies seen when the stage decides
};

class EarlyDecisionTest : public ::testing::TestWithParam<EarlyRow> {};

// Stamps clean over the first 32 cycles decide the clock there, so a single pass holds few frames;
// stamps with anything to watch wait for all 128.
TEST_P(EarlyDecisionTest, DecidesAsSoonAsTheStampsAllow) {
  const EarlyRow& row = GetParam();
  std::size_t fed = 0;
  std::optional<std::size_t> fed_at_decision;
  ClockStage stage(
      [&](std::uint64_t, std::int64_t, LinkType, const ByteReader&, const EcatFrame&, bool) {
        if (!fed_at_decision) fed_at_decision = fed;
      });
  EcatFrame frame;
  const std::vector<SimFrame>& frames = simulated();
  // The first frame that may carry process data: the cyclic frame's first copy.
  std::size_t first_cyclic = 0;
  for (std::size_t i = 0; i < frames.size() && !fed_at_decision; ++i) {
    const ByteReader bytes(frames[i].bytes.data(), frames[i].bytes.size());
    walkPacket(LinkType::Ethernet, bytes, frame);
    ++fed;
    if (first_cyclic == 0 && frame.mayCarryProcessData()) first_cyclic = fed;
    stage.onFrame(fed, row.stamper(i, frames[i].time_ns), LinkType::Ethernet, bytes, frame, true,
                  false);
  }
  ASSERT_TRUE(fed_at_decision) << "the stage never decided";
  EXPECT_EQ(clockSourceName(stage.choice().source), std::string("capture")) << stage.choice().why;
  // Two copies a cycle, the master's first; a few of the first cycles may pass unsampled.
  const std::size_t cycles = (*fed_at_decision - first_cyclic + 2) / 2;
  EXPECT_NEAR(static_cast<double>(cycles), static_cast<double>(row.cycles), 4.0)
      << stage.choice().why;
}

INSTANTIATE_TEST_SUITE_P(
    Stamps, EarlyDecisionTest,
    ::testing::Values(EarlyRow{"clean", steady(), StampAssessor::kEarlyCycles + 1},
                      // Late by up to a fifth of the 250 us cycle: fit, but not clean.
                      EarlyRow{"late_a_fifth", lateBy(50 * kUs), StampAssessor::kCycles + 1},
                      EarlyRow{"fine_quantum", quantisedTo(100 * kUs), StampAssessor::kCycles + 1}),
    test::rowName<EarlyRow>);

TEST(ClockStage, DropsEveryRecordsCopyAndCountsIt) {
  std::vector<Passed> passed;
  std::vector<std::uint64_t> dropped;
  ClockStage stage(
      [&](std::uint64_t number, std::int64_t time_ns, LinkType, const ByteReader&, const EcatFrame&,
          bool) {
        passed.push_back({number, time_ns});
      },
      [&](std::uint64_t number) { dropped.push_back(number); });
  run(steady(), stage, 2);
  const std::size_t frames = simulated().size();
  ASSERT_EQ(passed.size(), frames);
  EXPECT_EQ(stage.duplicates().count, frames);
  EXPECT_EQ(stage.duplicates().first_frame, 2u);
  ASSERT_EQ(dropped.size(), frames);
  for (std::size_t i = 0; i < frames; ++i) {
    EXPECT_EQ(passed[i].number, 2 * i + 1);
    EXPECT_EQ(dropped[i], 2 * i + 2);
  }
}

TEST(ClockStage, KeepsAMasterCopyThatRepeatsTheLastOneAfterItsReturn) {
  // Consecutive cycles whose master copies are byte for byte the same (idle axes, a master that
  // does not number its frames) are not duplicates: a returned copy came between them.
  std::vector<Passed> passed;
  ClockStage stage([&](std::uint64_t number, std::int64_t time_ns, LinkType, const ByteReader&,
                       const EcatFrame&, bool) {
    passed.push_back({number, time_ns});
  });
  run(steady(), stage);
  EXPECT_EQ(passed.size(), simulated().size());
  EXPECT_EQ(stage.duplicates().count, 0u);
}

}  // namespace
}  // namespace ncservo
