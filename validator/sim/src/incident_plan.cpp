#include "incident_plan.hpp"

#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo::sim {

namespace {
using Bus = BusFault::Kind;
using Quantity = Drift::Quantity;
// The first incident after the start-up, the enables and the speed ramps; the last one early
// enough for its recovery to be captured.
constexpr double kFirstIncidentS = 0.8;
constexpr double kAfterLastIncidentS = 0.6;
}  // namespace

// Each chain stays clear of the other rows' evidence: no set-point step, NC violation, lost
// cycle or temperature rise within the windows of another incident; the overtemperature comes
// last on its axis, so that no later fault there has a warm motor in its minute.
const std::vector<IncidentRow>& incidentRows(bool diagnosis) {
  static const std::vector<IncidentRow> all = {
      {.cause = "following-error",
       .kind = IncidentKind::DriveFault,
       .axis = 0,
       .description = "FollowerErr (E09) at a steady speed set point",
       .apply = [](IncidentActions& a) { a.driveFault(0, bits::kFollowing); }},
      {.cause = "following-error-after-step",
       .kind = IncidentKind::DriveFault,
       .axis = 1,
       .description = "the NC steps the speed set point to 3000 rpm in one cycle; FollowerErr "
                      "(E09) 25 ms later",
       .apply =
           [](IncidentActions& a) {
             a.nc(0, NcAction::SpeedStep, 3000);
             a.driveFault(25 * kMs, bits::kFollowing);
           }},
      {.cause = "overcurrent",
       .kind = IncidentKind::DriveFault,
       .axis = 2,
       .description = "the motor current climbs at 2000 A/s to 24 A (message codes 1 and 2); "
                      "CurrErr (E06)",
       .apply =
           [](IncidentActions& a) {
             a.drift(0, {.quantity = Quantity::MotorCurrent,
                         .per_second = 2000,
                         .trip = 24,
                         .cause = bits::kCurrentErr});
           }},
      {.cause = "communication-loss",
       .kind = IncidentKind::DriveFault,
       .axis = 3,
       .description = "the axis's slave misses the LRW of 2 cycles (WKC 3 short, COM-001); "
                      "ECatWatchDog (E31) 3 ms after",
       .apply =
           [](IncidentActions& a) {
             a.bus(0, {Bus::SkipAxisLrw});
             a.bus(1, {Bus::SkipAxisLrw});  // the next cycle (offsets below a cycle round up)
             a.driveFault(3 * kMs, bits::kEcatWatchdog);
           }},
      {.cause = "bus-voltage",
       .kind = IncidentKind::DriveFault,
       .axis = 0,
       .description = "the axis brakes to standstill and the DC bus climbs at 2400 V/s to 800 V "
                      "(message code 3); BVErr (E05); the speed again 250 ms after",
       .apply =
           [](IncidentActions& a) {
             a.nc(-100 * kMs, NcAction::Speed, 0);
             a.drift(-100 * kMs, {.quantity = Quantity::BusVoltage,
                                  .per_second = 2400,
                                  .trip = 800,
                                  .cause = bits::kBusVoltageErr});
             a.nc(250 * kMs, NcAction::Speed, 600);
           }},
      {.cause = "encoder",
       .kind = IncidentKind::DriveFault,
       .axis = 1,
       .description = "EncoderErr (E01)",
       .apply = [](IncidentActions& a) { a.driveFault(0, bits::kEncoderErr); }},
      {.cause = "overspeed",
       .kind = IncidentKind::DriveFault,
       .axis = 2,
       .description = "OverSpeed (E11)",
       .apply = [](IncidentActions& a) { a.driveFault(0, bits::kOverspeed); }},
      {.cause = "configuration",
       .kind = IncidentKind::DriveFault,
       .axis = 3,
       .description = "the NC selects parameter table 5; PTBLCHKSErr (E30) 20 ms later",
       .apply =
           [](IncidentActions& a) {
             a.nc(-20 * kMs, NcAction::Table, 5);
             a.driveFault(0, bits::kParamChecksum);
           }},
      {.cause = "nc-command",
       .kind = IncidentKind::DriveFault,
       .axis = 0,
       .description = "the NC sets reserved SCW bit 20 for 5 cycles (SCW-001); SRTErr 10 ms "
                      "after it began",
       .apply =
           [](IncidentActions& a) {
             a.nc(-10 * kMs, NcAction::ReservedBit, 5);
             a.driveFault(0, bits::kServoRuntime);
           }},
      {.cause = "unknown",
       .kind = IncidentKind::DriveFault,
       .axis = 1,
       .description = "PDPINT (E16), a power stage fault with nothing before it",
       .apply = [](IncidentActions& a) { a.driveFault(0, bits::kPdpint); }},
      {.cause = "sync-error",
       .kind = IncidentKind::Esm,
       .axis = 2,
       .description = "the axis's slave falls from OP to SAFE-OP with AL status code 0x001A; the "
                      "master's AL status poll (every 10 ms) sees it, acknowledges it and "
                      "requests OP; the NC enables the axis again",
       .apply = [](IncidentActions& a) { a.fallFromOp(0, ecat::kAlCodeSyncError); }},
      {.cause = "link-fault",
       .kind = IncidentKind::DriveFault,
       .axis = 3,
       .description = "with --diagnosis: the cable into port 0 of the axis's slave corrupts 3 "
                      "frames; the drives from that slave on raise ECatTErr (E15), and the "
                      "master's next read of the error counters names the link",
       .apply = [](IncidentActions& a) { a.badLink(0, kTelegramFailureLimit); },
       .diagnosis = true},
      {.cause = "communication-loss",
       .kind = IncidentKind::BusOutage,
       .axis = -1,
       .description = "12 cycles are lost before the slaves (COM-004, COM-005); every drive "
                      "raises ECatTErr (E15), four drive faults",
       .apply =
           [](IncidentActions& a) {
             a.bus(0, {Bus::LoseBeforeSlaves, 12});
           }},
      {.cause = "overtemperature",
       .kind = IncidentKind::DriveFault,
       .axis = 3,
       .description = "the motor temperature climbs at 200 °C/s (message code 4), "
                      "SSW.TempWarning above 80 °C, I2t_Endat (E19) at 96 °C",
       .apply =
           [](IncidentActions& a) {
             a.drift(-300 * kMs, {.quantity = Quantity::MotorTemperature,
                                  .per_second = 200,
                                  .trip = 96,
                                  .cause = bits::kI2tEndat});
           }},
  };
  static const std::vector<IncidentRow> without = [] {
    std::vector<IncidentRow> rows;
    for (const IncidentRow& row : all) {
      if (!row.diagnosis) rows.push_back(row);
    }
    return rows;
  }();
  return diagnosis ? all : without;
}

double incidentTime(std::size_t row, std::size_t rows, double duration_s) {
  const double span = duration_s - kFirstIncidentS - kAfterLastIncidentS;
  return kFirstIncidentS + span * static_cast<double>(row) / static_cast<double>(rows - 1);
}

}  // namespace ncservo::sim
