// The `incidents` scenario (docs/simulate.md#incidents): a day at the machine compressed into the
// run, one incident per cause row of `validate`'s incidents, each preceded by the chain its row
// needs and cleared before the next. One row per incident; the rows say what the simulator does
// and which incidents the truth (--incidents-truth) lists.
#pragma once

#include <cstdint>
#include <vector>

#include "ncservo/incidents/incident.hpp"
#include "ncservo/sim/faults.hpp"
#include "ncservo/sim/models.hpp"

namespace ncservo::sim {

// What an incident's chain can do, relative to its time and on its axis.
class IncidentActions {
 public:
  virtual void nc(std::int64_t offset_ns, NcAction action, double value = 0) = 0;
  virtual void driveFault(std::int64_t offset_ns, std::uint32_t cause) = 0;
  virtual void drift(std::int64_t offset_ns, Drift drift) = 0;  // drift.from_ns: unused
  virtual void bus(std::int64_t offset_ns, BusFault fault) = 0;
  virtual void fallFromOp(std::int64_t offset_ns, std::uint16_t al_status_code) = 0;
  // The cable into port 0 of the axis's slave corrupts `frames` frames (--bad-link): the drives
  // from that slave on miss them.
  virtual void badLink(std::int64_t offset_ns, int frames) = 0;

 protected:
  ~IncidentActions() = default;
};

// The kinds and cause ids are the detector's own (docs/incidents.md): a drive fault is
// SEW.ServoErrors rising on the row's axis; the bus outage makes every drive raise ECatTErr
// afterwards (drive faults with cause communication-loss); an ESM row's axis's slave falls from OP.

struct IncidentRow {
  // The cause id the incident must get, as docs/incidents.md names it: written here, not taken
  // from the cause table the validator judges with, so that the truth is the plan's own.
  const char* cause;
  IncidentKind kind;
  int axis;                 // -1: the whole bus
  const char* description;  // the chain, for docs/simulate.md
  void (*apply)(IncidentActions& actions);
  bool diagnosis = false;  // only with --diagnosis: its evidence is what the ESCs said
};

// In the order they happen, evenly spaced over the run's quiet part; with --diagnosis or not.
const std::vector<IncidentRow>& incidentRows(bool diagnosis);

// The scenario's shortest run, and where its incidents fall (seconds of capture time).
inline constexpr double kIncidentsMinDuration = 6.0;
double incidentTime(std::size_t row, std::size_t rows, double duration_s);

// The telegram failure limit the bus outage exceeds (docs/rules.md COM-005's default).
inline constexpr int kTelegramFailureLimit = 3;

}  // namespace ncservo::sim
