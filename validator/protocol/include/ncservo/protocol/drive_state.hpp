// The drive state named from the process data (docs/protocol.md §6), as a first-match table.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "ncservo/protocol/pdo.hpp"

namespace ncservo {

enum class DriveState : std::uint8_t {
  Error,                 // the drive's state 8
  FaultReactionActive,   // 7
  DriveStop,             // 5b
  ControlActive,         // 5
  EnabledPowerStageOff,  // not one of the drive's numbered states
  SwitchedOn,            // 4
  ReadyToSwitchOn,       // 3
  NotReadyToSwitchOn,    // 1
};

const char* driveStateName(DriveState state);

// Inputs of the state table, one bit each.
enum StateInput : std::uint8_t {
  kInError = 1 << 0,    // SEW.ServoErrors
  kInEnabled = 1 << 1,  // SSW.ServoEn
  kInEmgon = 1 << 2,    // SCW.EMGON (1 = normal)
  kInBrake = 1 << 3,    // SCW.Brake (1 = normal)
  kInPulse = 1 << 4,    // SSW.PulseEnabled
  kInReady = 1 << 5,    // SSW.ServoRDY
};
inline constexpr unsigned kStateInputCount = 6;

struct StateRow {
  std::uint8_t mask;
  std::uint8_t value;
  DriveState state;
};

// Rows of docs/protocol.md §6, written so that exactly one matches any input (a unit test checks).
inline constexpr std::array<StateRow, 9> kStateRows{{
    {kInError | kInEnabled, kInError, DriveState::Error},
    {kInError | kInEnabled, kInError | kInEnabled, DriveState::FaultReactionActive},
    {kInError | kInEnabled | kInEmgon, kInEnabled, DriveState::DriveStop},
    {kInError | kInEnabled | kInEmgon | kInBrake, kInEnabled | kInEmgon, DriveState::DriveStop},
    {kInError | kInEnabled | kInEmgon | kInBrake | kInPulse,
     kInEnabled | kInEmgon | kInBrake | kInPulse, DriveState::ControlActive},
    {kInError | kInEnabled | kInEmgon | kInBrake | kInPulse, kInEnabled | kInEmgon | kInBrake,
     DriveState::EnabledPowerStageOff},
    {kInError | kInEnabled | kInPulse, kInPulse, DriveState::SwitchedOn},
    {kInError | kInEnabled | kInPulse | kInReady, kInReady, DriveState::ReadyToSwitchOn},
    {kInError | kInEnabled | kInPulse | kInReady, 0, DriveState::NotReadyToSwitchOn},
}};

DriveState driveStateFor(std::uint8_t inputs);

// The state shown by inputs (TxPDO) and, when known, outputs (RxPDO; unknown EMGON/Brake count
// as normal). Without inputs there is no state.
std::optional<DriveState> driveState(const PdoValues& values);

}  // namespace ncservo
