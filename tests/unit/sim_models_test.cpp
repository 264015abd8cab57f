// The simulator's drive and NC models (sim_models.hpp), stepped cycle by cycle (1 ms) with
// hand-made process data, against docs/protocol.md §1–5 and the timeouts of docs/rules.md.
#include <gtest/gtest.h>

#include <cctype>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "frame_builder.hpp"
#include "ncservo/sim/models.hpp"
#include "row_name.hpp"

namespace ncservo::sim {
namespace {

using test::rowName;

constexpr std::int64_t kMs = 1'000'000;
// The default timeouts (docs/rules.md), in milliseconds.
constexpr int kDriveResponseMs = 20;
constexpr int kEnableResponseMs = 100;
constexpr int kClearResponseMs = 100;
constexpr int kFaultReactionMs = 100;
constexpr int kParamTableMs = 50;
// A legal enable reaches ServoEn within this (the model's delay is a few milliseconds).
constexpr int kEnableWithinMs = 10;

std::uint32_t bitsOf(const TxPdo& in) {
  return in.ssw;
}
bool servoEn(const TxPdo& in) {
  return (in.ssw & bits::kServoEn) != 0;
}
bool servoRdy(const TxPdo& in) {
  return (in.ssw & bits::kServoRdy) != 0;
}
bool summary(const TxPdo& in) {
  return (in.sew & bits::kServoErrors) != 0;
}
bool zpAck(const TxPdo& in) {
  return (in.ssw & bits::kZPulseAck) != 0;
}
bool clearAck(const TxPdo& in) {
  return (in.ssw & bits::kErrClearAck) != 0;
}
int sswTableOf(const TxPdo& in) {
  const std::uint32_t low = (in.ssw & bits::kSswPrmtbl) >> 8;
  const std::uint32_t high = (in.ssw & bits::kSswExtPrmtbl) >> 12;
  return static_cast<int>(high * 4 + low + 1);
}
std::int32_t lowWords(const TxPdo& in) {
  return static_cast<std::int32_t>(static_cast<std::uint64_t>(in.actpos) & 0xFFFFFFFFU);
}
std::int32_t highWords(const TxPdo& in) {
  return static_cast<std::int32_t>(static_cast<std::uint64_t>(in.actpos) >> 32);
}

struct Scw {
  std::uint32_t se = 0;
  bool emgon = true;
  bool brake = true;
  std::uint32_t extra = 0;  // other SCW bits (ErrorClear, ZPulseRequest, table)
  std::int32_t ssp = 0;
};
RxPdo rx(const Scw& s) {
  RxPdo pdo;
  pdo.ssp = s.ssp;
  pdo.scw = s.se | (s.emgon ? bits::kEmgon : 0U) | (s.brake ? bits::kBrake : 0U) | s.extra;
  return pdo;
}
std::int32_t sspOf(double rpm) {
  return static_cast<std::int32_t>(rpm * kSspPerRpm);
}

// A drive stepped once per millisecond from time 0.
class Bench {
 public:
  explicit Bench(const DriveSetup& setup) : drive(setup) {}

  const TxPdo& step(const std::optional<RxPdo>& outputs) {
    if (outputs) {
      drive.step(&*outputs, now);
    } else {
      drive.step(nullptr, now);
    }
    now += kMs;
    return drive.inputs();
  }
  // `ms` cycles of the same outputs; how many of them showed `pred`.
  int hold(int ms, const RxPdo& outputs, const std::function<bool(const TxPdo&)>& pred = {}) {
    int count = 0;
    for (int i = 0; i < ms; ++i) {
      const TxPdo& in = step(outputs);
      if (pred && pred(in)) ++count;
    }
    return count;
  }
  // Steps until `pred` holds; the number of cycles it took (1 = the first), or `limit` + 1.
  int until(const RxPdo& outputs, const std::function<bool(const TxPdo&)>& pred, int limit) {
    for (int i = 1; i <= limit; ++i) {
      if (pred(step(outputs))) return i;
    }
    return limit + 1;
  }
  // A legal enable (SE 0x1 for 5 ms, then 0x2); the cycles from the edge to ServoEn.
  int enable(std::int32_t ssp = 0) {
    hold(5, rx({bits::kSePrepare, true, true, 0, 0}));
    return until(rx({bits::kSeEnable, true, true, 0, ssp}), servoEn, 300);
  }
  // ErrorClear with SE 0 until ErrClearAck, then 0 until it falls.
  void clearErrors() {
    until(rx({0, true, true, bits::kErrorClear}), clearAck, 400);
    until(
        rx({}), [](const TxPdo& in) { return !clearAck(in); }, 400);
  }

  DriveModel drive;
  std::int64_t now = 0;
};

DriveSetup absoluteAxis(std::uint64_t seed = 1) {
  DriveSetup s;
  s.axis = 0;
  s.incremental = false;
  s.seed = seed;
  return s;
}
DriveSetup incrementalAxis(std::uint64_t seed = 1) {
  DriveSetup s;
  s.axis = 1;
  s.incremental = true;
  s.seed = seed;
  return s;
}

// --- enable (docs/protocol.md §2) ---

struct EnableRow {
  const char* name;
  std::uint32_t before;  // SE held for 10 ms before 0x2
  bool emgon;
  bool error_latched;
  bool enables;
};

class DriveEnable : public ::testing::TestWithParam<EnableRow> {};

TEST_P(DriveEnable, OnlyAfterALegalEdge) {
  const EnableRow& row = GetParam();
  for (std::uint64_t seed : {1, 2, 3, 4, 5}) {
    Bench b(absoluteAxis(seed));
    b.hold(10, rx({}));
    if (row.error_latched) {
      b.drive.raiseFault(bits::kFollowing);
      b.hold(5, rx({}));
      ASSERT_TRUE(summary(b.drive.inputs()));
    }
    b.hold(10, rx({row.before, row.emgon}));
    const int took = b.until(rx({bits::kSeEnable, row.emgon}), servoEn, 200);
    if (row.enables) {
      EXPECT_LE(took, kEnableWithinMs) << row.name << " seed " << seed;
    } else {
      EXPECT_GT(took, 200) << row.name << " seed " << seed;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Rows, DriveEnable,
                         ::testing::Values(EnableRow{"0->2", 0x0, true, false, false},
                                           EnableRow{"3->2", 0x3, true, false, false},
                                           EnableRow{"1->2", 0x1, true, false, true},
                                           EnableRow{"1->2 EMGON 0", 0x1, false, false, false},
                                           EnableRow{"1->2 error latched", 0x1, true, true, false}),
                         rowName<EnableRow>);

struct DisableRow {
  std::uint32_t se_after;  // what SE becomes after 0x2
  bool disables;
};
class DriveDisable : public ::testing::TestWithParam<DisableRow> {};

TEST_P(DriveDisable, WithinDriveResponseOnceSeLeavesTwo) {
  const DisableRow& row = GetParam();
  for (std::uint64_t seed : {1, 2, 3, 4, 5}) {
    Bench b(absoluteAxis(seed));
    ASSERT_LE(b.enable(), kEnableWithinMs);
    const int took = b.until(
        rx({row.se_after}), [](const TxPdo& in) { return !servoEn(in); }, 200);
    if (row.disables) {
      EXPECT_LE(took, kDriveResponseMs) << "SE " << row.se_after << " seed " << seed;
    } else {
      EXPECT_GT(took, 200) << "SE " << row.se_after << " seed " << seed;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Rows, DriveDisable,
                         ::testing::Values(DisableRow{0x2, false}, DisableRow{0x1, true},
                                           DisableRow{0x0, true}, DisableRow{0x3, true}));

// --- ServoRDY (docs/protocol.md §5, the Servo_Ready_Mode table) ---

struct ReadyRow {
  int mode;
  bool enabled;
  bool error;
  bool ready;
};
class DriveReady : public ::testing::TestWithParam<ReadyRow> {};

TEST_P(DriveReady, FollowsTheServoReadyModeTable) {
  const ReadyRow& row = GetParam();
  DriveSetup setup = absoluteAxis();
  setup.ready_mode = row.mode;
  Bench b(setup);
  b.hold(10, rx({}));
  RxPdo outputs = rx({});
  if (row.enabled) {
    ASSERT_LE(b.enable(), kEnableWithinMs);
    outputs = rx({bits::kSeEnable});
  }
  if (row.error) b.drive.raiseFault(bits::kFollowing);
  const TxPdo& in = b.step(outputs);  // one cycle: the fault reaction has not ended yet
  ASSERT_EQ(servoEn(in), row.enabled);
  ASSERT_EQ(summary(in), row.error);
  EXPECT_EQ(servoRdy(in), row.ready);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, DriveReady,
    ::testing::Values(ReadyRow{0, false, false, true}, ReadyRow{0, true, false, true},
                      ReadyRow{0, false, true, false}, ReadyRow{0, true, true, false},
                      ReadyRow{1, false, false, false}, ReadyRow{1, false, true, false},
                      ReadyRow{1, true, false, true}, ReadyRow{1, true, true, false}));

// --- zero-pulse handshake (docs/protocol.md §1, §3) ---

struct ZeroPulseRow {
  const char* name;
  bool incremental;
  double rpm;
  bool acknowledged;
};
class DriveZeroPulse : public ::testing::TestWithParam<ZeroPulseRow> {};

TEST_P(DriveZeroPulse, AckAfterAZeroPulseWhileMoving) {
  const ZeroPulseRow& row = GetParam();
  Bench b(row.incremental ? incrementalAxis() : absoluteAxis());
  ASSERT_LE(b.enable(sspOf(row.rpm)), kEnableWithinMs);
  b.hold(100, rx({bits::kSeEnable, true, true, 0, sspOf(row.rpm)}));
  EXPECT_EQ((bitsOf(b.drive.inputs()) & bits::kIncremental) != 0, row.incremental);
  if (row.incremental) {
    EXPECT_EQ(highWords(b.drive.inputs()), 0) << "no zero pulse latched yet";
  }

  const RxPdo request = rx({bits::kSeEnable, true, true, bits::kZPulseRequest, sspOf(row.rpm)});
  TxPdo before = b.drive.inputs();
  int took = 0;
  for (took = 1; took <= 600; ++took) {
    const TxPdo now = b.step(request);
    if (zpAck(now)) {
      // The latched position (words 2-3) is a zero pulse the axis just crossed.
      EXPECT_EQ(highWords(now) % DriveModel::kIncrementalCountsPerRev, 0) << highWords(now);
      EXPECT_GE(highWords(now), lowWords(before));
      EXPECT_LE(highWords(now), lowWords(now));
      break;
    }
    before = now;
  }
  if (!row.acknowledged) {
    EXPECT_GT(took, 600) << row.name;
    return;
  }
  ASSERT_LE(took, 600) << row.name;
  // At 300 rpm with 10000 counts per revolution a zero pulse comes every 200 ms.
  EXPECT_LE(took, 210);
  const std::int32_t latched = highWords(b.drive.inputs());
  EXPECT_EQ(b.hold(20, request, zpAck), 20) << "the ack holds while the request does";
  const RxPdo released = rx({bits::kSeEnable, true, true, 0, sspOf(row.rpm)});
  EXPECT_LE(b.until(
                released, [](const TxPdo& in) { return !zpAck(in); }, 100),
            kDriveResponseMs);
  EXPECT_EQ(b.hold(50, released, zpAck), 0) << "the ack stays down";
  // Later zero pulses update words 2-3 (docs/protocol.md §1).
  b.hold(400, released);
  EXPECT_NE(highWords(b.drive.inputs()), latched);
  EXPECT_EQ(highWords(b.drive.inputs()) % DriveModel::kIncrementalCountsPerRev, 0);
}

INSTANTIATE_TEST_SUITE_P(Rows, DriveZeroPulse,
                         ::testing::Values(ZeroPulseRow{"incremental_moving", true, 300, true},
                                           ZeroPulseRow{"incremental_standstill", true, 0, false},
                                           ZeroPulseRow{"absolute_moving", false, 300, false}),
                         rowName<ZeroPulseRow>);

// --- error clear (FAULT RESET) ---

struct ClearRow {
  const char* name;
  bool error;
  bool error_clear;
  bool acknowledged;
};
class DriveErrorClear : public ::testing::TestWithParam<ClearRow> {};

TEST_P(DriveErrorClear, Handshake) {
  const ClearRow& row = GetParam();
  Bench b(absoluteAxis());
  b.hold(10, rx({}));
  if (row.error) b.drive.raiseFault(bits::kFollowing);
  b.hold(5, rx({}));
  ASSERT_EQ(summary(b.drive.inputs()), row.error);
  const RxPdo clear = rx({0, true, true, row.error_clear ? bits::kErrorClear : 0U});
  const int took = b.until(clear, clearAck, 300);
  if (!row.acknowledged) {
    EXPECT_GT(took, 300) << row.name;
    EXPECT_EQ(summary(b.drive.inputs()), row.error) << "the error stays latched";
    return;
  }
  EXPECT_LE(took, kClearResponseMs) << row.name;
  EXPECT_EQ(b.drive.inputs().sew, 0U) << "errors cleared with the ack";
  EXPECT_EQ(b.hold(30, clear, clearAck), 30) << "the ack holds while ErrorClear does";
  EXPECT_LE(b.until(
                rx({}), [](const TxPdo& in) { return !clearAck(in); }, 100),
            kDriveResponseMs);
  EXPECT_EQ(b.hold(50, rx({}), clearAck), 0);
}

INSTANTIATE_TEST_SUITE_P(Rows, DriveErrorClear,
                         ::testing::Values(ClearRow{"error_and_clear", true, true, true},
                                           ClearRow{"error_no_clear", true, false, false},
                                           ClearRow{"no_error_no_clear", false, false, false}),
                         rowName<ClearRow>);

// --- parameter table ---

struct TableRow {
  int commanded;
};
class DriveTable : public ::testing::TestWithParam<TableRow> {};

TEST_P(DriveTable, FollowedWithinParamTable) {
  const int table = GetParam().commanded;
  for (std::uint64_t seed : {1, 2, 3}) {
    Bench b(absoluteAxis(seed));
    b.hold(10, rx({}));
    ASSERT_EQ(sswTableOf(b.drive.inputs()), 1);
    const RxPdo outputs = rx({0, true, true, bits::scwTable(table)});
    const int took = b.until(
        outputs, [&](const TxPdo& in) { return sswTableOf(in) == table; }, 200);
    EXPECT_LE(took, table == 1 ? 1 : kParamTableMs) << "table " << table << " seed " << seed;
    EXPECT_EQ(b.hold(100, outputs, [&](const TxPdo& in) { return sswTableOf(in) != table; }), 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Rows, DriveTable,
                         ::testing::Values(TableRow{1}, TableRow{2}, TableRow{4}, TableRow{5},
                                           TableRow{8}));

// --- ECatTErr: no data for 3 cycles (docs/protocol.md §4) ---

struct TimeoutRow {
  const char* pattern;  // per cycle: 'L' lost (step(nullptr)), '.' outputs arrive
  bool operational;
  bool timeout;
};
class DriveEcatTimeout : public ::testing::TestWithParam<TimeoutRow> {};

TEST_P(DriveEcatTimeout, AfterThreeMissedCycles) {
  const TimeoutRow& row = GetParam();
  Bench b(absoluteAxis());
  b.drive.setOperational(row.operational);
  b.hold(10, rx({}));
  bool seen = false;
  for (const char* c = row.pattern; *c != '\0'; ++c) {
    const TxPdo& in = b.step(*c == 'L' ? std::nullopt : std::optional<RxPdo>(rx({})));
    seen = seen || (in.sew & bits::kEcatTimeout) != 0;
  }
  seen = seen ||
         b.hold(10, rx({}), [](const TxPdo& in) { return (in.sew & bits::kEcatTimeout) != 0; }) > 0;
  EXPECT_EQ(seen, row.timeout) << row.pattern;
  if (row.timeout) {
    EXPECT_TRUE(summary(b.drive.inputs()));
  }
}

INSTANTIATE_TEST_SUITE_P(Rows, DriveEcatTimeout,
                         ::testing::Values(TimeoutRow{"LL", true, false},
                                           TimeoutRow{"LLL", true, true},
                                           TimeoutRow{"LL.LL", true, false},
                                           TimeoutRow{"LLLLL", true, true},
                                           TimeoutRow{"LLLLL", false, false}));

// --- fault reaction ---

struct FaultRow {
  bool fault;
  bool disables;
};
class DriveFaultReaction : public ::testing::TestWithParam<FaultRow> {};

TEST_P(DriveFaultReaction, DisablesWithinFaultReaction) {
  const FaultRow& row = GetParam();
  for (std::uint64_t seed : {1, 2, 3, 4, 5}) {
    Bench b(absoluteAxis(seed));
    const RxPdo running = rx({bits::kSeEnable, true, true, 0, sspOf(1000)});
    ASSERT_LE(b.enable(sspOf(1000)), kEnableWithinMs);
    b.hold(100, running);
    if (row.fault) b.drive.raiseFault(bits::kFollowing);
    const int took = b.until(
        running, [](const TxPdo& in) { return !servoEn(in); }, 300);
    if (row.disables) {
      EXPECT_LE(took, kFaultReactionMs) << "seed " << seed;
      EXPECT_EQ(b.drive.inputs().sew, bits::kFollowing | bits::kServoErrors);
    } else {
      EXPECT_GT(took, 300) << "seed " << seed;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Rows, DriveFaultReaction,
                         ::testing::Values(FaultRow{true, true}, FaultRow{false, false}));

// --- message codes (docs/protocol.md §5) ---

TEST(DriveMessages, CodesStayInZeroToFiveAndAllAppear) {
  for (const DriveSetup& setup : {absoluteAxis(), incrementalAxis()}) {
    Bench b(setup);
    std::vector<int> seen(6, 0);
    const RxPdo running = rx({bits::kSeEnable, true, true, 0, sspOf(800)});
    b.enable(sspOf(800));
    for (int i = 0; i < 300; ++i) {
      const std::int32_t code = b.step(running).msg_code;
      ASSERT_GE(code, 0);
      ASSERT_LE(code, 5);
      ++seen[static_cast<std::size_t>(code)];
    }
    for (int code = 0; code < 6; ++code) EXPECT_GT(seen[code], 0) << "code " << code;
  }
}

// --- N=0 and N=Ns ---

struct SpeedRow {
  const char* name;
  double rpm;     // set point
  int settle_ms;  // after the enable
  bool n_zero;
  bool n_setpoint;
};
class DriveSpeedBits : public ::testing::TestWithParam<SpeedRow> {};

TEST_P(DriveSpeedBits, NZeroAndNSetpoint) {
  const SpeedRow& row = GetParam();
  Bench b(absoluteAxis());
  ASSERT_LE(b.enable(0), kEnableWithinMs);
  b.hold(10, rx({bits::kSeEnable}));
  const RxPdo running = rx({bits::kSeEnable, true, true, 0, sspOf(row.rpm)});
  b.hold(row.settle_ms, running);
  const TxPdo& in = b.drive.inputs();
  EXPECT_EQ((in.ssw & bits::kNZero) != 0, row.n_zero) << row.name << " at " << b.drive.speedRpm();
  EXPECT_EQ((in.ssw & bits::kNSetpoint) != 0, row.n_setpoint)
      << row.name << " at " << b.drive.speedRpm();
}

INSTANTIATE_TEST_SUITE_P(Rows, DriveSpeedBits,
                         ::testing::Values(SpeedRow{"standstill", 0, 50, true, true},
                                           SpeedRow{"accelerating", 3000, 5, false, false},
                                           SpeedRow{"at_speed", 1000, 300, false, true},
                                           SpeedRow{"reverse_at_speed", -1000, 300, false, true}),
                         rowName<SpeedRow>);

// --- misbehaviours: each produces its deviation, on the first occasion only ---

// One occasion of a quirk's situation; the deviation it produced (ms, or cycles, or 0/1).
using Occasion = std::function<int(Bench&)>;

int idleCount(Bench& b, int ms, const std::function<bool(const TxPdo&)>& pred) {
  return b.hold(ms, rx({}), pred);
}

struct QuirkRow {
  const char* name;
  DriveQuirk quirk;
  bool incremental;
  int threshold;  // the rule's limit: the deviation must exceed it once, never otherwise
  Occasion occasion;
};

const std::vector<QuirkRow>& quirkRows() {
  static const std::vector<QuirkRow> rows = {
      {"SpuriousEnable", DriveQuirk::SpuriousEnable, false, 0,
       [](Bench& b) { return idleCount(b, 100, servoEn); }},
      {"LateDisable", DriveQuirk::LateDisable, false, kDriveResponseMs,
       [](Bench& b) {
         b.enable();
         const int on = b.hold(150, rx({bits::kSePrepare}), servoEn);
         b.hold(10, rx({}));
         return on;
       }},
      {"IgnoreEnable", DriveQuirk::IgnoreEnable, false, kEnableResponseMs,
       [](Bench& b) {
         const int took = b.enable();
         b.hold(10, rx({bits::kSePrepare}));
         b.hold(20, rx({}));
         return took;
       }},
      {"HoldZPulseAck", DriveQuirk::HoldZPulseAck, true, kDriveResponseMs,
       [](Bench& b) {
         const std::int32_t ssp = sspOf(300);
         b.enable(ssp);
         b.until(rx({bits::kSeEnable, true, true, bits::kZPulseRequest, ssp}), zpAck, 600);
         const int held = b.hold(150, rx({bits::kSeEnable, true, true, 0, ssp}), zpAck);
         b.hold(10, rx({bits::kSePrepare}));
         b.hold(50, rx({}));
         return held;
       }},
      {"SpuriousZPulseAck", DriveQuirk::SpuriousZPulseAck, false, 0,
       [](Bench& b) { return idleCount(b, 100, zpAck); }},
      {"SpuriousClearAck", DriveQuirk::SpuriousClearAck, false, 0,
       [](Bench& b) { return idleCount(b, 100, clearAck); }},
      {"HoldClearAck", DriveQuirk::HoldClearAck, false, kDriveResponseMs,
       [](Bench& b) {
         b.drive.raiseFault(bits::kFollowing);
         b.hold(5, rx({}));
         b.until(rx({0, true, true, bits::kErrorClear}), clearAck, 400);
         const int held = b.hold(150, rx({}), clearAck);
         b.hold(30, rx({}));
         return held;
       }},
      {"IgnoreClear", DriveQuirk::IgnoreClear, false, kClearResponseMs,
       [](Bench& b) {
         b.drive.raiseFault(bits::kFollowing);
         b.hold(5, rx({}));
         const int took = b.until(rx({0, true, true, bits::kErrorClear}), clearAck, 400);
         b.until(
             rx({}), [](const TxPdo& in) { return !clearAck(in); }, 400);
         b.hold(30, rx({}));
         return took;
       }},
      {"CauseWithoutSummary", DriveQuirk::CauseWithoutSummary, false, 0,
       [](Bench& b) {
         return idleCount(
             b, 100, [](const TxPdo& in) { return (in.sew & kSewCauseMask) != 0 && !summary(in); });
       }},
      {"SummaryWithoutCause", DriveQuirk::SummaryWithoutCause, false, kDriveResponseMs,
       [](Bench& b) {
         return idleCount(
             b, 150, [](const TxPdo& in) { return summary(in) && (in.sew & kSewCauseMask) == 0; });
       }},
      {"ReservedErrorBit", DriveQuirk::ReservedErrorBit, false, 0,
       [](Bench& b) {
         return idleCount(b, 100,
                          [](const TxPdo& in) { return (in.sew & bits::kSewReserved) != 0; });
       }},
      {"ReservedStatusBit", DriveQuirk::ReservedStatusBit, false, 0,
       [](Bench& b) {
         return idleCount(b, 100,
                          [](const TxPdo& in) { return (in.ssw & bits::kSswReserved) != 0; });
       }},
      {"ReadyInverted", DriveQuirk::ReadyInverted, false, kDriveResponseMs,
       [](Bench& b) {
         // Servo_Ready_Mode 0, no error: ServoRDY 1 (docs/protocol.md §5)
         return idleCount(b, 150, [](const TxPdo& in) { return !servoRdy(in); });
       }},
      {"SlowFaultReaction", DriveQuirk::SlowFaultReaction, false, kFaultReactionMs,
       [](Bench& b) {
         const std::int32_t ssp = sspOf(1000);
         b.enable(ssp);
         b.hold(50, rx({bits::kSeEnable, true, true, 0, ssp}));
         b.drive.raiseFault(bits::kFollowing);
         const int on = b.hold(300, rx({bits::kSeEnable, true, true, 0, ssp}),
                               [](const TxPdo& in) { return servoEn(in) && summary(in); });
         b.hold(5, rx({bits::kSePrepare}));
         b.clearErrors();
         b.hold(10, rx({}));
         return on;
       }},
      {"IgnoreTable", DriveQuirk::IgnoreTable, false, kParamTableMs,
       [](Bench& b) {
         const int took = b.until(
             rx({0, true, true, bits::scwTable(5)}),
             [](const TxPdo& in) { return sswTableOf(in) == 5; }, 300);
         b.until(
             rx({}), [](const TxPdo& in) { return sswTableOf(in) == 1; }, 300);
         return took;
       }},
      {"UndefinedMessage", DriveQuirk::UndefinedMessage, false, 0,
       [](Bench& b) {
         return idleCount(b, 100,
                          [](const TxPdo& in) { return in.msg_code < 0 || in.msg_code > 5; });
       }},
      {"SilentTimeout", DriveQuirk::SilentTimeout, false, 0,
       [](Bench& b) {
         for (int i = 0; i < 3; ++i) b.step(std::nullopt);
         const int reported =
             b.hold(30, rx({}), [](const TxPdo& in) { return (in.sew & bits::kEcatTimeout) != 0; });
         b.clearErrors();
         b.hold(10, rx({}));
         return reported > 0 ? 0 : 1;  // the deviation: no ECatTErr
       }},
  };
  return rows;
}

class DriveQuirks : public ::testing::TestWithParam<std::size_t> {};

TEST_P(DriveQuirks, DeviationOnTheFirstOccasionOnly) {
  const QuirkRow& row = quirkRows()[GetParam()];
  for (bool armed : {false, true}) {
    Bench b(row.incremental ? incrementalAxis() : absoluteAxis());
    b.hold(10, rx({}));
    if (armed) b.drive.arm(row.quirk, b.now);
    const int first = row.occasion(b);
    b.hold(50, rx({}));
    const int second = row.occasion(b);
    if (armed) {
      EXPECT_GT(first, row.threshold) << row.name << ": no deviation";
    } else {
      EXPECT_LE(first, row.threshold) << row.name << ": deviation without the quirk";
    }
    EXPECT_LE(second, row.threshold) << row.name << (armed ? " armed" : "") << ": second occasion";
  }
}

INSTANTIATE_TEST_SUITE_P(Rows, DriveQuirks, ::testing::Range<std::size_t>(0, 17),
                         [](const ::testing::TestParamInfo<std::size_t>& row) {
                           return std::string(quirkRows()[row.param].name);
                         });

TEST(DriveQuirks, EveryQuirkHasARow) {
  ASSERT_EQ(quirkRows().size(), 17U);
  for (int q = 0; q <= static_cast<int>(DriveQuirk::SilentTimeout); ++q) {
    int rows = 0;
    for (const QuirkRow& row : quirkRows()) rows += static_cast<int>(row.quirk) == q;
    EXPECT_EQ(rows, 1) << "quirk " << q;
  }
}

// --- NC axis ---

// An NC axis and a drive exchanging process data once per millisecond (no bus in between).
struct NcRecord {
  RxPdo out;                  // what the NC sent
  std::optional<TxPdo> seen;  // the inputs the NC had when it sent it
  TxPdo in;                   // the drive's answer
};
class Loop {
 public:
  Loop(bool incremental, bool operational = true)
      : nc(incremental), drive(incremental ? incrementalAxis() : absoluteAxis()) {
    nc.setOperational(operational);
    drive.setOperational(operational);
  }
  void run(int ms, const std::function<void(Loop&)>& each = {}) {
    for (int i = 0; i < ms; ++i) {
      if (each) each(*this);
      const std::optional<TxPdo> seen = latest;
      const RxPdo out = nc.step(seen ? &*seen : nullptr, now);
      drive.step(&out, now);
      latest = drive.inputs();
      records.push_back({out, seen, drive.inputs()});
      now += kMs;
    }
  }
  std::int64_t ms() const { return now / kMs; }

  NcAxis nc;
  DriveModel drive;
  std::optional<TxPdo> latest;
  std::vector<NcRecord> records;
  std::int64_t now = 0;
};

std::uint32_t seOf(const RxPdo& out) {
  return out.scw & bits::kSe;
}
// SE as runs: each value with how many cycles it lasted.
std::vector<std::pair<std::uint32_t, int>> seRuns(const std::vector<NcRecord>& records) {
  std::vector<std::pair<std::uint32_t, int>> runs;
  for (const NcRecord& r : records) {
    if (runs.empty() || runs.back().first != seOf(r.out)) runs.push_back({seOf(r.out), 0});
    ++runs.back().second;
  }
  return runs;
}
std::string runsText(const std::vector<std::pair<std::uint32_t, int>>& runs) {
  std::string text;
  for (const auto& [se, n] : runs) text += std::to_string(se) + "x" + std::to_string(n) + " ";
  return text;
}

struct NcSeRow {
  const char* name;
  std::vector<NcEvent> events;
  bool operational;
  bool enable_before_op;
  std::vector<std::uint32_t> se_runs;  // SE values in order
  bool servo_en_at_end;
};
class NcEnableSequence : public ::testing::TestWithParam<NcSeRow> {};

TEST_P(NcEnableSequence, SeRuns) {
  const NcSeRow& row = GetParam();
  Loop loop(false, row.operational);
  loop.nc.setEnableBeforeOp(row.enable_before_op);
  for (const NcEvent& e : row.events) loop.nc.schedule(e);
  loop.run(250);
  const auto runs = seRuns(loop.records);
  std::vector<std::uint32_t> values;
  for (const auto& run : runs) values.push_back(run.first);
  EXPECT_EQ(values, row.se_runs) << row.name << ": " << runsText(runs);
  for (std::size_t i = 1; i < runs.size(); ++i) {
    if (runs[i].first == bits::kSeEnable && runs[i - 1].first == bits::kSePrepare) {
      EXPECT_GE(runs[i - 1].second, 3) << row.name << ": SE 0x1 held 3 cycles before 0x2";
    }
  }
  EXPECT_EQ(servoEn(loop.drive.inputs()), row.servo_en_at_end) << row.name;
}

INSTANTIATE_TEST_SUITE_P(
    Rows, NcEnableSequence,
    ::testing::Values(
        NcSeRow{"enable", {{10 * kMs, NcAction::Enable}}, true, false, {0, 1, 2}, true},
        NcSeRow{
            "illegal_enable", {{10 * kMs, NcAction::IllegalEnable}}, true, false, {0, 2}, false},
        NcSeRow{"enable_then_disable",
                {{10 * kMs, NcAction::Enable}, {150 * kMs, NcAction::Disable}},
                true,
                false,
                {0, 1, 2, 1, 0},
                false},
        NcSeRow{"no_plan", {}, true, false, {0}, false},
        NcSeRow{"not_operational", {{10 * kMs, NcAction::Enable}}, false, false, {0}, false},
        NcSeRow{"not_operational_enable_before_op",
                {{10 * kMs, NcAction::Enable}},
                false,
                true,
                {1},
                false}),
    rowName<NcSeRow>);

// On a drive error the NC holds SE until ServoEn falls, clears the error with the handshake,
// then enables again with a legal edge.
struct NcFaultRow {
  const char* name;
  double hold_clear_ms;  // NcAction::HoldErrorClear, 0 = none
};
class NcFaultHandling : public ::testing::TestWithParam<NcFaultRow> {};

TEST_P(NcFaultHandling, HoldsClearsAndReenables) {
  const NcFaultRow& row = GetParam();
  Loop loop(false);
  loop.nc.schedule({10 * kMs, NcAction::Enable});
  loop.nc.schedule({50 * kMs, NcAction::Speed, 500});
  if (row.hold_clear_ms > 0) {
    loop.nc.schedule({100 * kMs, NcAction::HoldErrorClear, row.hold_clear_ms});
  }
  constexpr int kFaultAt = 150;
  loop.run(600, [](Loop& l) {
    if (l.ms() == kFaultAt) l.drive.raiseFault(bits::kFollowing);
  });
  const auto& rec = loop.records;
  ASSERT_TRUE(servoEn(*rec[kFaultAt].seen)) << "enabled before the fault";

  // The first cycle in which the NC saw ServoEn 0 after the fault.
  std::size_t off = kFaultAt;
  while (off < rec.size() && servoEn(*rec[off].seen)) ++off;
  ASSERT_LT(off, rec.size());
  for (std::size_t k = kFaultAt; k < off; ++k) {
    EXPECT_EQ(seOf(rec[k].out), bits::kSeEnable) << "SE held while the drive reacts, at " << k;
    EXPECT_EQ(rec[k].out.scw & bits::kErrorClear, 0U) << k;
  }
  // ErrorClear rises once the drive is off, and is held until the NC saw ErrClearAck.
  std::size_t clear_from = off;
  while (clear_from < rec.size() && (rec[clear_from].out.scw & bits::kErrorClear) == 0) {
    ++clear_from;
  }
  ASSERT_LT(clear_from, rec.size());
  EXPECT_LE(clear_from - off, 1U);
  std::size_t ack_seen = clear_from;
  while (ack_seen < rec.size() && !clearAck(*rec[ack_seen].seen)) ++ack_seen;
  ASSERT_LT(ack_seen, rec.size());
  std::size_t clear_to = ack_seen;
  while (clear_to < rec.size() && (rec[clear_to].out.scw & bits::kErrorClear) != 0) ++clear_to;
  ASSERT_LT(clear_to, rec.size());
  const auto held = static_cast<double>(clear_to - ack_seen);
  EXPECT_GE(held, row.hold_clear_ms) << row.name;
  EXPECT_LE(held, row.hold_clear_ms + 1) << row.name;
  for (std::size_t k = clear_from; k < clear_to; ++k) {
    EXPECT_EQ(seOf(rec[k].out), bits::kSePrepare) << k;
  }
  // Re-enable: SE 0x2 again only after the ack fell, reached from 0x1; the drive follows.
  std::size_t ack_gone = clear_to;
  while (ack_gone < rec.size() && clearAck(*rec[ack_gone].seen)) ++ack_gone;
  std::size_t again = clear_to;
  while (again < rec.size() && seOf(rec[again].out) != bits::kSeEnable) ++again;
  ASSERT_LT(again, rec.size());
  EXPECT_GE(again, ack_gone);
  EXPECT_EQ(seOf(rec[again - 1].out), bits::kSePrepare);
  EXPECT_TRUE(servoEn(loop.drive.inputs()));
  EXPECT_EQ(loop.drive.inputs().sew, 0U);
  // Never an illegal edge.
  const auto runs = seRuns(rec);
  for (std::size_t i = 1; i < runs.size(); ++i) {
    if (runs[i].first == bits::kSeEnable) {
      EXPECT_EQ(runs[i - 1].first, bits::kSePrepare) << runsText(runs);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Rows, NcFaultHandling,
                         ::testing::Values(NcFaultRow{"prompt", 0},
                                           NcFaultRow{"hold_error_clear_100ms", 100}),
                         rowName<NcFaultRow>);

struct ReservedRow {
  std::optional<double> cycles;  // NcAction::ReservedBit, none = not scheduled
  int expected;
};
class NcReservedBit : public ::testing::TestWithParam<ReservedRow> {};

TEST_P(NcReservedBit, SetForTheGivenCycles) {
  const ReservedRow& row = GetParam();
  Loop loop(false);
  loop.nc.schedule({10 * kMs, NcAction::Enable});
  if (row.cycles) loop.nc.schedule({100 * kMs, NcAction::ReservedBit, *row.cycles});
  loop.run(200);
  int set = 0;
  for (const NcRecord& r : loop.records) set += (r.out.scw & bits::kScwReserved) != 0;
  EXPECT_EQ(set, row.expected);
}

INSTANTIATE_TEST_SUITE_P(Rows, NcReservedBit,
                         ::testing::Values(ReservedRow{std::nullopt, 0}, ReservedRow{5.0, 5},
                                           ReservedRow{1.0, 1}));

// --- PDO encoding (docs/protocol.md §1) ---

struct RxRow {
  RxPdo pdo;
};
class RxEncoding : public ::testing::TestWithParam<RxRow> {};

TEST_P(RxEncoding, MatchesTheSpecBytesAndRoundTrips) {
  const RxPdo& pdo = GetParam().pdo;
  test::Bytes bytes(10, 0xEE);
  encodeRx(pdo, bytes.data());
  EXPECT_EQ(bytes, test::rxPdo(pdo.ssp, pdo.scw, pdo.ext_code));
  const RxPdo back = decodeRx(bytes.data());
  EXPECT_EQ(back.ssp, pdo.ssp);
  EXPECT_EQ(back.scw, pdo.scw);
  EXPECT_EQ(back.ext_code, pdo.ext_code);
}

INSTANTIATE_TEST_SUITE_P(Rows, RxEncoding,
                         ::testing::Values(RxRow{{0, 0, 0}}, RxRow{{123456, 0x406, 7}},
                                           RxRow{{-600000, 0x80001E06U, -2}},
                                           RxRow{{INT32_MIN, 0xFFFFFFFFU, INT16_MIN}},
                                           RxRow{{INT32_MAX, 0x1A3D, INT16_MAX}}));

struct TxRow {
  TxPdo pdo;
};
class TxEncoding : public ::testing::TestWithParam<TxRow> {};

TEST_P(TxEncoding, MatchesTheSpecOffsets) {
  const TxPdo& pdo = GetParam().pdo;
  test::Bytes bytes(40, 0xEE);
  encodeTx(pdo, bytes.data());
  EXPECT_EQ(bytes, test::txPdo(test::TxValues(pdo.actpos, pdo.ssw, pdo.sew, pdo.msg_code,
                                              pdo.msg_data, pdo.ext_data)));
  // A few offsets spelled out: SSW at 8, SEW at 12, message code at 16 (little-endian).
  EXPECT_EQ(bytes[8], static_cast<std::uint8_t>(pdo.ssw));
  EXPECT_EQ(bytes[15], static_cast<std::uint8_t>(pdo.sew >> 24));
  EXPECT_EQ(bytes[16], static_cast<std::uint8_t>(pdo.msg_code));
  EXPECT_EQ(bytes[7], static_cast<std::uint8_t>(static_cast<std::uint64_t>(pdo.actpos) >> 56));
}

INSTANTIATE_TEST_SUITE_P(
    Rows, TxEncoding,
    ::testing::Values(
        TxRow{TxPdo{}},
        TxRow{TxPdo{0x0001D4C000123456LL, 0x10FB, 0x80001, 3, 561.5F, {1.0F, -2.5F, 3.25F, 41.5F}}},
        TxRow{TxPdo{-1, 0xFFFFFFFFU, 0x02000000U, 7, -0.0F, {0, 0, 0, 1e30F}}}));

struct TableBitsRow {
  int table;
  std::uint32_t scw;  // PRMTBL bits 5..4, ExtPRMTBL bit 12 (docs/protocol.md §2)
  std::uint32_t ssw;  // PRMTBL bits 9..8, ExtPRMTBL bit 12 (§3)
};
class TableBits : public ::testing::TestWithParam<TableBitsRow> {};

TEST_P(TableBits, ScwAndSswBits) {
  const TableBitsRow& row = GetParam();
  EXPECT_EQ(bits::scwTable(row.table), row.scw);
  EXPECT_EQ(bits::sswTable(row.table), row.ssw);
  EXPECT_EQ(bits::tableOfScw(row.scw), row.table);
  // Other SCW bits do not disturb the selection.
  EXPECT_EQ(bits::tableOfScw(row.scw | 0x80000F0FU), row.table);
}

INSTANTIATE_TEST_SUITE_P(
    Rows, TableBits,
    ::testing::Values(TableBitsRow{1, 0x0000, 0x0000}, TableBitsRow{2, 0x0010, 0x0100},
                      TableBitsRow{3, 0x0020, 0x0200}, TableBitsRow{4, 0x0030, 0x0300},
                      TableBitsRow{5, 0x1000, 0x1000}, TableBitsRow{6, 0x1010, 0x1100},
                      TableBitsRow{7, 0x1020, 0x1200}, TableBitsRow{8, 0x1030, 0x1300}));

}  // namespace
}  // namespace ncservo::sim
