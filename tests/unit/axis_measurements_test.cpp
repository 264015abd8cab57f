// What an axis's model measures for the incidents' causes (axis_measurements.hpp): the rises of
// SEW and SSW bits, the messages as they stood before a fault, set-point steps and the motor
// temperature's minute. One row per case.
#include "ncservo/model/axis_measurements.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <vector>

#include "ncservo/protocol/word_bits.hpp"
#include "row_name.hpp"

namespace ncservo {
namespace {

constexpr std::int32_t kCurrentCode = 1;  // motor current (docs/protocol.md §5)

struct Inputs {
  std::uint32_t ssw = 0;
  std::uint32_t sew = 0;
  std::int32_t code = 0;
  float data = 0;
};

PdoValues inputsOf(const Inputs& in) {
  PdoValues v;
  v.has_tx = true;
  v.set(Word::Ssw, in.ssw);
  v.set(Word::Sew, in.sew);
  v.set(Word::MsgCode, static_cast<std::uint32_t>(in.code));
  v.setFloat(Word::MsgData, in.data);
  return v;
}

Mark markAt(std::uint64_t frame) {
  return Mark{frame, static_cast<std::int64_t>(frame) * kMsNs, static_cast<std::int64_t>(frame)};
}

std::optional<double> current(const MessageHistory& h) {
  for (std::size_t i = 0; i < kBefore.size(); ++i) {
    if (kBefore[i].message_code == kCurrentCode) return h.before[i];
  }
  return std::nullopt;
}

struct FaultRow {
  const char* name;
  std::vector<Inputs> frames;          // frames 1, 2, ...
  bool rose_at_last;                   // takeInputs said ServoErrors rose in the last frame
  std::optional<double> before_fault;  // messagesBefore(last).current
  std::optional<double> now;           // messages().current
};

const FaultRow kFaultRows[] = {
    {"FaultSeesTheMessagesBeforeItsFrame",
     {{0, 0, kCurrentCode, 5.0f}, {0, bits::kServoErrors | 0x100, kCurrentCode, 9.0f}},
     true,
     5.0,
     9.0},
    {"NoFaultOnTheFirstInputs", {{0, bits::kServoErrors, kCurrentCode, 7.0f}}, false, 7.0, 7.0},
    {"ErrorsHeldAreNoRise",
     {{0, bits::kServoErrors, kCurrentCode, 1.0f}, {0, bits::kServoErrors, kCurrentCode, 2.0f}},
     false,
     2.0,
     2.0},
    {"OtherCodeLeavesTheCurrent",
     {{0, 0, kCurrentCode, 3.0f}, {0, bits::kServoErrors, kMotorTemperatureCode, 60.0f}},
     true,
     3.0,
     3.0},
};

class FaultRows : public ::testing::TestWithParam<FaultRow> {};

TEST_P(FaultRows, MessagesBeforeTheFault) {
  const FaultRow& row = GetParam();
  AxisMeasurements m;
  bool rose = false;
  std::uint64_t frame = 0;
  for (const Inputs& in : row.frames) rose = m.takeInputs(inputsOf(in), markAt(++frame));
  EXPECT_EQ(rose, row.rose_at_last);
  EXPECT_EQ((m.sewRoseIn(frame) & bits::kServoErrors) != 0, row.rose_at_last);
  EXPECT_EQ(current(m.messagesBefore(frame)), row.before_fault);
  EXPECT_EQ(current(m.messages()), row.now);
  // A later frame sees the messages as they stand.
  EXPECT_EQ(current(m.messagesBefore(frame + 1)), row.now);
}

INSTANTIATE_TEST_SUITE_P(AxisMeasurements, FaultRows, ::testing::ValuesIn(kFaultRows),
                         test::rowName<FaultRow>);

struct StepRow {
  const char* name;
  std::vector<std::int32_t> set_points;
  std::size_t steps;  // confirmed
  bool candidate;     // a step waiting for its next cycle
};

const StepRow kStepRows[] = {
    {"StillThenStepThenStill", {0, 1, 0, 1, 0, 5000, 5001}, 1, false},
    {"StepAwaitsItsNextCycle", {0, 1, 0, 1, 0, 5000}, 0, true},
    {"RampIsNoStep", {0, 1000, 2000, 3000, 4000, 5000, 6000}, 0, false},
    {"TooFewCyclesBefore", {0, 1, 0, 5000, 5001}, 0, false},
    {"BelowTheMinimum", {0, 1, 0, 1, 0, 99, 99}, 0, false},
    {"RampStartIsNoStep", {0, 1, 0, 1, 0, 5000, 10000}, 0, false},
};

class StepRows : public ::testing::TestWithParam<StepRow> {};

TEST_P(StepRows, SetPointSteps) {
  const StepRow& row = GetParam();
  AxisMeasurements m;
  std::uint64_t frame = 0;
  for (std::int32_t ssp : row.set_points) m.takeSetPoint(ssp, markAt(++frame));
  EXPECT_EQ(m.steps().size(), row.steps);
  EXPECT_EQ(m.stepCandidate().has_value(), row.candidate);
}

INSTANTIATE_TEST_SUITE_P(AxisMeasurements, StepRows, ::testing::ValuesIn(kStepRows),
                         test::rowName<StepRow>);

TEST(AxisMeasurementsReset, WindowsStartAfreshTheLastValuesStay) {
  AxisMeasurements m;
  m.takeInputs(inputsOf({0, 0, kMotorTemperatureCode, 40.0f}), markAt(1));
  m.takeInputs(inputsOf({0, bits::kFollowing, kCurrentCode, 2.0f}), markAt(2));
  ASSERT_TRUE(m.followingRose());
  ASSERT_TRUE(m.messages().temperature_last_at);
  m.reset();
  EXPECT_FALSE(m.followingRose());
  EXPECT_FALSE(m.inputsKnown());
  EXPECT_FALSE(m.messages().temperature_last_at);
  EXPECT_EQ(current(m.messages()), 2.0);  // what the drive said last is still what it said
  // The first inputs after a reset are no rise, whatever they hold.
  EXPECT_FALSE(m.takeInputs(inputsOf({0, bits::kServoErrors, 0, 0}), markAt(3)));
}

}  // namespace
}  // namespace ncservo
