// The drive state table (drive_state.hpp) against docs/protocol.md §6.
#include "ncservo/protocol/drive_state.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "frame_builder.hpp"

namespace ncservo {
namespace {

constexpr unsigned kAllInputs = 1u << kStateInputCount;

std::string inputsText(unsigned in) {
  std::string text;
  const std::pair<unsigned, const char*> names[] = {{kInError, "error"}, {kInEnabled, "enabled"},
                                                    {kInEmgon, "emgon"}, {kInBrake, "brake"},
                                                    {kInPulse, "pulse"}, {kInReady, "ready"}};
  for (const auto& [bit, name] : names) {
    if (in & bit) text += std::string(text.empty() ? "" : "+") + name;
  }
  return text.empty() ? "none" : text;
}

// docs/protocol.md §6 written as it reads: rows tried in order, the first that matches wins.
DriveState specState(unsigned in) {
  const bool error = in & kInError, enabled = in & kInEnabled, emgon = in & kInEmgon,
             brake = in & kInBrake, pulse = in & kInPulse, ready = in & kInReady;
  if (error && !enabled) return DriveState::Error;
  if (error && enabled) return DriveState::FaultReactionActive;
  if (enabled && (!emgon || !brake)) return DriveState::DriveStop;
  if (enabled && pulse) return DriveState::ControlActive;
  if (enabled && !pulse) return DriveState::EnabledPowerStageOff;
  if (!enabled && pulse) return DriveState::SwitchedOn;
  if (!enabled && !pulse && ready) return DriveState::ReadyToSwitchOn;
  return DriveState::NotReadyToSwitchOn;
}

TEST(DriveStateTable, ExactlyOneRowMatchesEveryInput) {
  for (unsigned in = 0; in < kAllInputs; ++in) {
    int matches = 0;
    for (const StateRow& row : kStateRows) matches += (in & row.mask) == row.value;
    EXPECT_EQ(matches, 1) << inputsText(in);
  }
}

TEST(DriveStateTable, RowsUseOnlyKnownInputs) {
  for (const StateRow& row : kStateRows) {
    EXPECT_EQ(row.mask & ~(kAllInputs - 1), 0u);
    EXPECT_EQ(row.value & ~row.mask, 0u) << "a row's value has bits outside its mask";
  }
}

TEST(DriveStateTable, AgreesWithTheSpecOrderForEveryInput) {
  for (unsigned in = 0; in < kAllInputs; ++in) {
    EXPECT_EQ(driveStateFor(static_cast<std::uint8_t>(in)), specState(in)) << inputsText(in);
  }
}

// One row per line of docs/protocol.md §6, with inputs that single it out.
struct StateCase {
  const char* name;
  unsigned inputs;
  DriveState state;
  const char* text;
};
constexpr unsigned kNormal = kInEmgon | kInBrake;
const StateCase kStateCases[] = {
    {"error, not enabled", kInError | kNormal | kInReady, DriveState::Error, "error"},
    {"error, not enabled, pulse", kInError | kInPulse, DriveState::Error, "error"},
    {"error and enabled", kInError | kInEnabled | kNormal | kInPulse,
     DriveState::FaultReactionActive, "fault reaction active"},
    {"error and enabled, EMGON 0", kInError | kInEnabled | kInBrake,
     DriveState::FaultReactionActive, "fault reaction active"},
    {"enabled, EMGON 0", kInEnabled | kInBrake | kInPulse, DriveState::DriveStop, "drive stop"},
    {"enabled, brake 0", kInEnabled | kInEmgon | kInPulse, DriveState::DriveStop, "drive stop"},
    {"enabled, EMGON 0 and brake 0", kInEnabled, DriveState::DriveStop, "drive stop"},
    {"enabled and pulse", kInEnabled | kNormal | kInPulse | kInReady, DriveState::ControlActive,
     "control active"},
    {"enabled, no pulse", kInEnabled | kNormal | kInReady, DriveState::EnabledPowerStageOff,
     "enabled, power stage off"},
    {"not enabled, pulse", kNormal | kInPulse | kInReady, DriveState::SwitchedOn, "switched on"},
    {"not enabled, pulse, EMGON 0", kInPulse, DriveState::SwitchedOn, "switched on"},
    {"ready", kNormal | kInReady, DriveState::ReadyToSwitchOn, "ready to switch on"},
    {"ready, EMGON 0 and brake 0", kInReady, DriveState::ReadyToSwitchOn, "ready to switch on"},
    {"nothing", 0, DriveState::NotReadyToSwitchOn, "not ready to switch on"},
    {"EMGON and brake only", kNormal, DriveState::NotReadyToSwitchOn, "not ready to switch on"},
};

TEST(DriveStateTable, RowsOfTheSpec) {
  for (const StateCase& c : kStateCases) {
    SCOPED_TRACE(c.name);
    const DriveState state = driveStateFor(static_cast<std::uint8_t>(c.inputs));
    EXPECT_EQ(state, c.state);
    EXPECT_STREQ(driveStateName(state), c.text);
  }
}

// driveState() reads the inputs from the words: one row per combination of PDOs present.
struct WordsCase {
  const char* name;
  bool has_rx;
  std::uint32_t scw;
  bool has_tx;
  std::uint32_t ssw;
  std::uint32_t sew;
  std::optional<DriveState> state;
};
constexpr std::uint32_t kServoEn = 0x1, kServoRdy = 0x2, kPulse = 0x80;
constexpr std::uint32_t kEmgon = 0x4, kBrake = 0x400, kSe2 = 0x2;
const WordsCase kWordsCases[] = {
    {"no PDOs", false, 0, false, 0, 0, std::nullopt},
    {"RxPDO only", true, kSe2 | kEmgon | kBrake, false, 0, 0, std::nullopt},
    {"TxPDO only: EMGON/brake count as normal", false, 0, true, kServoEn | kPulse, 0,
     DriveState::ControlActive},
    {"TxPDO only, enabled, no pulse", false, 0, true, kServoEn | kServoRdy, 0,
     DriveState::EnabledPowerStageOff},
    {"TxPDO only, error summary", false, 0, true, kServoEn, 0x80001,
     DriveState::FaultReactionActive},
    {"TxPDO only, ready", false, 0, true, kServoRdy, 0, DriveState::ReadyToSwitchOn},
    {"both, EMGON 0", true, kSe2 | kBrake, true, kServoEn | kPulse, 0, DriveState::DriveStop},
    {"both, brake 0", true, kSe2 | kEmgon, true, kServoEn | kPulse, 0, DriveState::DriveStop},
    {"both, normal", true, kSe2 | kEmgon | kBrake, true, kServoEn | kPulse, 0,
     DriveState::ControlActive},
    {"cause bit without summary is no error", false, 0, true, kServoRdy, 0x80000,
     DriveState::ReadyToSwitchOn},
    {"error, disabled", true, 0, true, kServoRdy, 0x1, DriveState::Error},
};

TEST(DriveState, FromPdoValues) {
  for (const WordsCase& c : kWordsCases) {
    SCOPED_TRACE(c.name);
    PdoValues values;
    values.has_rx = c.has_rx;
    values.has_tx = c.has_tx;
    values.raw[static_cast<std::size_t>(Word::Scw)] = c.scw;
    values.raw[static_cast<std::size_t>(Word::Ssw)] = c.ssw;
    values.raw[static_cast<std::size_t>(Word::Sew)] = c.sew;
    EXPECT_EQ(driveState(values), c.state);
  }
}

}  // namespace
}  // namespace ncservo
