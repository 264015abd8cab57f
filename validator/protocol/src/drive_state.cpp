#include "ncservo/protocol/drive_state.hpp"

#include "ncservo/protocol/word_bits.hpp"

namespace ncservo {

namespace {
using namespace bits;
}  // namespace

const char* driveStateName(DriveState state) {
  switch (state) {
    case DriveState::Error:
      return "error";
    case DriveState::FaultReactionActive:
      return "fault reaction active";
    case DriveState::DriveStop:
      return "drive stop";
    case DriveState::ControlActive:
      return "control active";
    case DriveState::EnabledPowerStageOff:
      return "enabled, power stage off";
    case DriveState::SwitchedOn:
      return "switched on";
    case DriveState::ReadyToSwitchOn:
      return "ready to switch on";
    case DriveState::NotReadyToSwitchOn:
      return "not ready to switch on";
  }
  return "unknown";
}

DriveState driveStateFor(std::uint8_t inputs) {
  for (const StateRow& row : kStateRows) {
    if ((inputs & row.mask) == row.value) return row.state;
  }
  return DriveState::NotReadyToSwitchOn;
}

std::optional<DriveState> driveState(const PdoValues& values) {
  if (!values.has_tx) return std::nullopt;
  const std::uint32_t ssw = values.ssw();
  std::uint8_t in = 0;
  if (values.sew() & kServoErrors) in |= kInError;
  if (ssw & kServoEn) in |= kInEnabled;
  if (ssw & kPulseEnabled) in |= kInPulse;
  if (ssw & kServoRdy) in |= kInReady;
  // Without the outputs, EMGON and Brake count as normal.
  const std::uint32_t scw = values.has_rx ? values.scw() : kEmgon | kBrake;
  if (scw & kEmgon) in |= kInEmgon;
  if (scw & kBrake) in |= kInBrake;
  return driveStateFor(in);
}

}  // namespace ncservo
