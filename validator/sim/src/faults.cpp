#include "ncservo/sim/faults.hpp"

namespace ncservo::sim {

namespace {
using Bus = BusFault::Kind;
using Said = DiagnosisFault::Kind;
constexpr ScenarioSlot kInStartup(int axis) {
  return {-1, axis};
}
}  // namespace

// The `faults` scenario spreads every rule over four axes and time, the bus faults last and
// apart, so that no two of them meet.
const std::vector<FaultRecipe>& faultRecipes() {
  static const std::vector<FaultRecipe> table = {
      {.rule = RuleId::Se001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {0.60, 0},
       .description =
           "the NC disables the axis, then enables it with SE 0x0 -> 0x2 (and later legally)",
       .apply =
           [](FaultActions& f) {
             f.nc(-150 * kMs, NcAction::Disable);
             f.nc(0, NcAction::IllegalEnable);
           }},
      {.rule = RuleId::Se002,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {1.05, 1},
       .description = "the drive shows ServoEn for 4 ms while the axis is disabled",
       .apply =
           [](FaultActions& f) {
             f.nc(-100 * kMs, NcAction::Disable);
             f.quirk(DriveQuirk::SpuriousEnable);
             f.nc(100 * kMs, NcAction::Enable);
           }},
      {.rule = RuleId::Se003,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {0.60, 2},
       .description = "the drive stays enabled 60 ms after the NC disables the axis",
       .apply =
           [](FaultActions& f) {
             f.nc(0, NcAction::Disable);
             f.quirk(DriveQuirk::LateDisable);
             f.nc(250 * kMs, NcAction::Enable);
           },
       // ServoEn with no enable requested, from the disable on (models.cpp kLateDisableNs)
       .standing_ns = 60 * kMs},
      {.rule = RuleId::Se004,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {0.60, 3},
       .description = "the drive takes 160 ms to follow a legal enable",
       .apply =
           [](FaultActions& f) {
             f.nc(-100 * kMs, NcAction::Disable);
             f.quirk(DriveQuirk::IgnoreEnable);
             f.nc(0, NcAction::Enable);
           }},
      {.rule = RuleId::Zp001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Incremental,
       .companions = {},
       .scenario = {0.60, 1},
       .description = "the drive keeps ZPulseAck 60 ms after the request falls",
       .apply =
           [](FaultActions& f) {
             f.nc(0, NcAction::ZeroPulse);
             f.quirk(DriveQuirk::HoldZPulseAck);
           }},
      {.rule = RuleId::Zp002,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {1.05, 3},
       .description = "the drive shows ZPulseAck for 4 ms with no request",
       .apply = [](FaultActions& f) { f.quirk(DriveQuirk::SpuriousZPulseAck); }},
      {.rule = RuleId::Zp003,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Absolute,
       .companions = {},
       .scenario = {1.05, 0},
       .description = "the NC requests a zero-pulse search for 30 ms on an absolute axis",
       .apply = [](FaultActions& f) { f.nc(0, NcAction::ZeroPulseAbsolute, 30); }},
      {.rule = RuleId::Ec001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {1.05, 2},
       .description = "the drive shows ErrClearAck for 4 ms with no ErrorClear",
       .apply = [](FaultActions& f) { f.quirk(DriveQuirk::SpuriousClearAck); }},
      {.rule = RuleId::Ec002,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {1.50, 1},
       .description = "a drive fault (E09); the NC holds ErrorClear 100 ms after ErrClearAck",
       .apply =
           [](FaultActions& f) {
             f.driveFault();
             f.nc(0, NcAction::HoldErrorClear, 100);
           }},
      {.rule = RuleId::Ec003,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {1.50, 2},
       .description =
           "a drive fault (E09); the drive keeps ErrClearAck 60 ms after ErrorClear falls",
       .apply =
           [](FaultActions& f) {
             f.driveFault();
             f.quirk(DriveQuirk::HoldClearAck);
           }},
      {.rule = RuleId::Ec004,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {1.50, 3},
       .description = "a drive fault (E09); the drive answers ErrorClear only after 160 ms",
       .apply =
           [](FaultActions& f) {
             f.driveFault();
             f.quirk(DriveQuirk::IgnoreClear);
           }},
      {.rule = RuleId::Sew001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.00, 1},
       .description = "the drive shows OverLoad for one cycle without the summary bit",
       .apply = [](FaultActions& f) { f.quirk(DriveQuirk::CauseWithoutSummary); }},
      {.rule = RuleId::Sew002,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.45, 3},
       .description = "the drive shows the summary bit without a cause for 50 ms",
       .apply = [](FaultActions& f) { f.quirk(DriveQuirk::SummaryWithoutCause); }},
      {.rule = RuleId::Sew003,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.45, 0},
       .description = "the drive sets reserved SEW bit 25 for one cycle",
       .apply = [](FaultActions& f) { f.quirk(DriveQuirk::ReservedErrorBit); }},
      {.rule = RuleId::Ssw001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.00, 3},
       .description = "the drive sets reserved SSW bit 13 for one cycle",
       .apply = [](FaultActions& f) { f.quirk(DriveQuirk::ReservedStatusBit); }},
      {.rule = RuleId::Scw001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.00, 2},
       .description = "the NC sets reserved SCW bit 20 for 5 cycles",
       .apply = [](FaultActions& f) { f.nc(0, NcAction::ReservedBit, 5); }},
      {.rule = RuleId::Rdy001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.45, 2},
       .description = "the drive inverts ServoRDY for 50 ms",
       .apply = [](FaultActions& f) { f.quirk(DriveQuirk::ReadyInverted); }},
      {.rule = RuleId::Flt001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {1.50, 0},
       .description = "a drive fault (E09) while enabled; the drive stays enabled 200 ms",
       .apply =
           [](FaultActions& f) {
             f.driveFault();
             f.quirk(DriveQuirk::SlowFaultReaction);
           },
       // ServoEn beside the error, from the fault on (models.cpp kSlowReactionNs)
       .standing_ns = 200 * kMs},
      {.rule = RuleId::Pt001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.45, 1},
       .description = "the NC selects table 8; the drive follows only after 120 ms",
       .apply =
           [](FaultActions& f) {
             f.nc(0, NcAction::Table, 8);
             f.quirk(DriveQuirk::IgnoreTable);
           }},
      {.rule = RuleId::Msg001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.00, 0},
       .description = "the drive sends message code 7 for one cycle",
       .apply = [](FaultActions& f) { f.quirk(DriveQuirk::UndefinedMessage); }},
      {.rule = RuleId::Com001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.90, 0},
       .description = "the axis's slave does not process one cycle's LRW (WKC 3 short)",
       .apply = [](FaultActions& f) { f.bus({Bus::SkipAxisLrw}); }},
      {.rule = RuleId::Com002,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::None,
       .companions = {},
       .scenario = {3.20, -1},
       .description = "the master sends nothing for 2 cycles",
       .apply =
           [](FaultActions& f) {
             f.bus({Bus::SkipCycles, 2});
           }},
      {.rule = RuleId::Com003,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {RuleId::Com004},
       .scenario = {3.40, 2},
       .description = "3 cycles are lost before the slaves; the axis's drive raises no ECatTErr",
       .apply =
           [](FaultActions& f) {
             f.quirk(DriveQuirk::SilentTimeout);
             f.bus({Bus::LoseBeforeSlaves, 3});
           }},
      {.rule = RuleId::Com004,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::None,
       .companions = {},
       .scenario = {3.05, -1},
       .description = "one cycle's frame is lost after the slaves",
       .apply = [](FaultActions& f) { f.bus({Bus::LoseAfterSlaves}); }},
      {.rule = RuleId::Com005,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::None,
       .companions = {RuleId::Com004},
       .scenario = {3.80, -1},
       .description = "4 cycles are lost before the slaves (the drives raise ECatTErr)",
       .apply =
           [](FaultActions& f) {
             f.bus({Bus::LoseBeforeSlaves, 4});
           }},
      {.rule = RuleId::Com006,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::None,
       .companions = {},
       .scenario = {3.60, -1},
       .description = "the master sends 6 cycles alternately a quarter cycle late and on time",
       .apply =
           [](FaultActions& f) {
             f.bus({Bus::JitterCycles, 6});
           }},
      {.rule = RuleId::Com007,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::None,
       .companions = {},
       .scenario = {3.70, -1},
       .description = "one cycle's frame comes back three quarters of a cycle late",
       .apply = [](FaultActions& f) { f.bus({Bus::LateReturn}); }},
      {.rule = RuleId::Esm001,
       .phase = FaultPhase::Startup,
       .need = AxisNeed::Any,
       .companions = {RuleId::Esm003},
       .scenario = kInStartup(0),
       .description =
           "the master requests OP from PRE-OP of the axis's slave (refused with 0x0011)",
       .apply = [](FaultActions& f) { f.startup(StartupFault::RequestOpFromPreOp); }},
      {.rule = RuleId::Esm002,
       .phase = FaultPhase::Startup,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = kInStartup(1),
       .description = "the NC sends SE 0x1 to the axis while its slave is in SAFE-OP",
       .apply = [](FaultActions& f) { f.startup(StartupFault::EnableBeforeOp); }},
      {.rule = RuleId::Esm003,
       .phase = FaultPhase::Startup,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = kInStartup(2),
       .description = "the axis's slave refuses SAFE-OP -> OP once (0x001D)",
       .apply = [](FaultActions& f) { f.startup(StartupFault::RefuseOp); }},
      {.rule = RuleId::Esm004,
       .phase = FaultPhase::Startup,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = kInStartup(3),
       .description =
           "the axis's slave powers up with an AL error (0x0050) that the master acknowledges",
       .apply = [](FaultActions& f) { f.startup(StartupFault::PowerUpError); }},
      {.rule = RuleId::Mbx001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.70, 0},
       .description = "the drive sends an emergency 0x8611 (following error) with no SEW cause bit",
       .apply =
           [](FaultActions& f) {
             f.diagnosis({.kind = Said::Mailbox, .quirk = MailboxQuirk::EmergencyWithoutFault});
           },
       .diagnosis = true},
      {.rule = RuleId::Mbx002,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.70, 1},
       .description = "the drive sends an error reset emergency, then 200 ms later faults (E09) "
                      "without an emergency",
       .apply =
           [](FaultActions& f) {
             f.diagnosis({.kind = Said::Mailbox,
                          .offset_ns = -200 * kMs,
                          .quirk = MailboxQuirk::ErrorResetNow});
             f.diagnosis({.kind = Said::Mailbox, .quirk = MailboxQuirk::SilentFault});
             f.driveFault();
           },
       .diagnosis = true},
      {.rule = RuleId::Mbx003,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.70, 3},
       .description = "the NC reads object 2000h:00, which the drive does not have (aborted "
                      "0x06020000)",
       .apply =
           [](FaultActions& f) {
             f.diagnosis({.kind = Said::NcRead, .index = 0x2000, .subindex = 0});
           },
       .diagnosis = true},
      {.rule = RuleId::Erh001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.20, 0},
       .description = "a drive fault (E09) the NC reads 1003h of; 150 ms later the drive loses "
                      "its history, and the NC reads 1003h:00 again",
       .apply =
           [](FaultActions& f) {
             f.driveFault();
             f.diagnosis({.kind = Said::Mailbox,
                          .offset_ns = 150 * kMs,
                          .quirk = MailboxQuirk::LoseHistory});
             f.diagnosis(
                 {.kind = Said::NcRead, .offset_ns = 200 * kMs, .index = 0x1003, .subindex = 0});
           },
       .diagnosis = true},
      {.rule = RuleId::Erh002,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.70, 2},
       .description = "a drive fault (E09) whose 1003h entry carries 0x1000, not 0x8611",
       .apply =
           [](FaultActions& f) {
             f.diagnosis({.kind = Said::Mailbox, .quirk = MailboxQuirk::WrongHistoryCode});
             f.driveFault();
           },
       .diagnosis = true},
      {.rule = RuleId::Lnk001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {RuleId::Com004},
       .scenario = {2.80, 2},
       .description = "the cable into port 0 of the axis's slave corrupts 2 frames (--bad-link)",
       .apply = [](FaultActions& f) { f.diagnosis({.kind = Said::CorruptFrames, .amount = 2}); },
       .diagnosis = true},
      {.rule = RuleId::Lnk002,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.20, 1},
       .description = "the cable into port 0 of the axis's slave goes down and up between two "
                      "frames: both ends count a lost link",
       .apply = [](FaultActions& f) { f.diagnosis({.kind = Said::LinkDown}); },
       .diagnosis = true},
      {.rule = RuleId::Dc001,
       .phase = FaultPhase::Cycle,
       .need = AxisNeed::Any,
       .companions = {},
       .scenario = {2.20, 3},
       .description = "the axis's slave's system time difference (0x092C) is -5000 ns for 250 ms",
       .apply =
           [](FaultActions& f) {
             f.diagnosis({.kind = Said::TimeDifference, .amount = -5000, .for_ns = 250 * kMs});
           },
       .diagnosis = true},
  };
  return table;
}

const FaultRecipe* faultRecipe(RuleId rule) {
  for (const FaultRecipe& recipe : faultRecipes()) {
    if (recipe.rule == rule) return &recipe;
  }
  return nullptr;
}

std::vector<RuleId> companionsOf(RuleId rule) {
  const FaultRecipe* recipe = faultRecipe(rule);
  return recipe != nullptr ? recipe->companions : std::vector<RuleId>{};
}
const char* faultDescription(RuleId rule) {
  const FaultRecipe* recipe = faultRecipe(rule);
  return recipe != nullptr ? recipe->description : "not injectable: the simulator has no recipe";
}

}  // namespace ncservo::sim
