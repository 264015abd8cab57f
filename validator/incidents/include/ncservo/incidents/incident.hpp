// An incident (docs/incidents.md): a drive fault, a bus outage or a slave's fall from OP, with
// what came before it, its cause from one table of cause rows, and its recovery.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ncservo/base/stamp.hpp"
#include "ncservo/model/axis_model.hpp"

namespace ncservo {

enum class IncidentKind : std::uint8_t { DriveFault, BusOutage, Esm };
// "drive-fault", "bus-outage", "esm": as JSON names the kind.
const char* incidentKindName(IncidentKind kind);

// The cause rows, in the order they are tried (docs/incidents.md#causes): public ids.
enum class CauseId : std::uint8_t {
  LinkFault,
  CommunicationLoss,
  SyncError,
  Overtemperature,
  FollowingErrorAfterStep,
  FollowingError,
  Overcurrent,
  BusVoltage,
  Encoder,
  Overspeed,
  Configuration,
  NcCommand,
  Unknown,
};
inline constexpr std::size_t kCauseCount = 13;

// The last AL status code (0x0134) read of a slave, and where (the cause sync-error).
struct AlCodeMark {
  std::uint16_t code = 0;
  Mark at;
};

// A frame the incident's chain passes through, with a short text.
struct IncidentEvidence {
  Stamp at;  // the frame's own capture time
  std::string what;
};

struct Incident {
  IncidentKind kind = IncidentKind::DriveFault;
  std::optional<std::uint16_t> axis;      // none: the bus, or a slave that is no axis
  std::optional<std::uint16_t> station;   // ESM: the slave's station address, where known
  std::optional<std::uint16_t> position;  // ESM: its ring position, where known
  Stamp at;                               // the incident's frame
  Stamp end;                              // its recovery, or the capture's last frame
  bool recovered = false;
  bool ended = false;                   // recovered, or followed by another fault of its axis first
  std::string what;                     // ESM: "OP → SAFE-OP (AL status 0x0014)"
  std::vector<const SewCause*> errors;  // the SEW cause bits set at the fault, in bit order
  CauseId cause = CauseId::Unknown;
  std::string cause_text;
  std::vector<IncidentEvidence> evidence;                      // in frame order
  std::array<std::optional<double>, kBefore.size()> before{};  // by kBefore row
  std::array<Stamp, kBefore.size()> before_at{};               // the frame each came in
  std::optional<Stamp> error_clear;                            // SEW.ServoErrors fell; ESM: none
  std::optional<Stamp> reenabled;                              // enabled again (ESM: back in OP)
  // Among the incidents of its kind, axis (or station) and cause in its capture segment, from 1:
  // what a baseline matches it by (docs/baselines.md#fingerprints).
  std::uint32_t ordinal = 0;
};

// The SEW bit's filter name without "ncservo.sew." ("ecat_watchdog"), and its label with the
// E-code ("ECatWatchDog (E31)"), both from the field table.
std::string sewBitName(const SewCause& cause);
const char* sewBitLabel(const SewCause& cause);
// "axis1 fault E19", "bus outage", "station 0x1002 OP → SAFE-OP": what a text line calls it.
std::string incidentHeadline(const Incident& incident, const std::string& axis_name);

}  // namespace ncservo
