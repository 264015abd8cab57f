#include "ncservo/sim/faults.hpp"

namespace ncservo::sim {

namespace {
using Bus = BusFault::Kind;
constexpr ScenarioSlot kInStartup(int axis) {
  return {-1, axis};
}
}  // namespace

// The `faults` scenario spreads every rule over four axes and time, the bus faults last and
// apart, so that no two of them meet.
const std::vector<FaultRecipe>& faultRecipes() {
  static const std::vector<FaultRecipe> table = {
      {RuleId::Se001,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {0.60, 0},
       "the NC disables the axis, then enables it with SE 0x0 -> 0x2 (and later legally)",
       [](FaultActions& f) {
         f.nc(-150 * kMs, NcAction::Disable);
         f.nc(0, NcAction::IllegalEnable);
       }},
      {RuleId::Se002,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {1.05, 1},
       "the drive shows ServoEn for 4 ms while the axis is disabled",
       [](FaultActions& f) {
         f.nc(-100 * kMs, NcAction::Disable);
         f.quirk(DriveQuirk::SpuriousEnable);
         f.nc(100 * kMs, NcAction::Enable);
       }},
      {RuleId::Se003,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {0.60, 2},
       "the drive stays enabled 60 ms after the NC disables the axis",
       [](FaultActions& f) {
         f.nc(0, NcAction::Disable);
         f.quirk(DriveQuirk::LateDisable);
         f.nc(250 * kMs, NcAction::Enable);
       }},
      {RuleId::Se004,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {0.60, 3},
       "the drive takes 160 ms to follow a legal enable",
       [](FaultActions& f) {
         f.nc(-100 * kMs, NcAction::Disable);
         f.quirk(DriveQuirk::IgnoreEnable);
         f.nc(0, NcAction::Enable);
       }},
      {RuleId::Zp001,
       FaultPhase::Cycle,
       AxisNeed::Incremental,
       {},
       {0.60, 1},
       "the drive keeps ZPulseAck 60 ms after the request falls",
       [](FaultActions& f) {
         f.nc(0, NcAction::ZeroPulse);
         f.quirk(DriveQuirk::HoldZPulseAck);
       }},
      {RuleId::Zp002,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {1.05, 3},
       "the drive shows ZPulseAck for 4 ms with no request",
       [](FaultActions& f) { f.quirk(DriveQuirk::SpuriousZPulseAck); }},
      {RuleId::Zp003,
       FaultPhase::Cycle,
       AxisNeed::Absolute,
       {},
       {1.05, 0},
       "the NC requests a zero-pulse search for 30 ms on an absolute axis",
       [](FaultActions& f) { f.nc(0, NcAction::ZeroPulseAbsolute, 30); }},
      {RuleId::Ec001,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {1.05, 2},
       "the drive shows ErrClearAck for 4 ms with no ErrorClear",
       [](FaultActions& f) { f.quirk(DriveQuirk::SpuriousClearAck); }},
      {RuleId::Ec002,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {1.50, 1},
       "a drive fault (E09); the NC holds ErrorClear 100 ms after ErrClearAck",
       [](FaultActions& f) {
         f.driveFault();
         f.nc(0, NcAction::HoldErrorClear, 100);
       }},
      {RuleId::Ec003,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {1.50, 2},
       "a drive fault (E09); the drive keeps ErrClearAck 60 ms after ErrorClear falls",
       [](FaultActions& f) {
         f.driveFault();
         f.quirk(DriveQuirk::HoldClearAck);
       }},
      {RuleId::Ec004,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {1.50, 3},
       "a drive fault (E09); the drive answers ErrorClear only after 160 ms",
       [](FaultActions& f) {
         f.driveFault();
         f.quirk(DriveQuirk::IgnoreClear);
       }},
      {RuleId::Sew001,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {2.00, 1},
       "the drive shows OverLoad for one cycle without the summary bit",
       [](FaultActions& f) { f.quirk(DriveQuirk::CauseWithoutSummary); }},
      {RuleId::Sew002,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {2.45, 3},
       "the drive shows the summary bit without a cause for 50 ms",
       [](FaultActions& f) { f.quirk(DriveQuirk::SummaryWithoutCause); }},
      {RuleId::Sew003,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {2.45, 0},
       "the drive sets reserved SEW bit 25 for one cycle",
       [](FaultActions& f) { f.quirk(DriveQuirk::ReservedErrorBit); }},
      {RuleId::Ssw001,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {2.00, 3},
       "the drive sets reserved SSW bit 13 for one cycle",
       [](FaultActions& f) { f.quirk(DriveQuirk::ReservedStatusBit); }},
      {RuleId::Scw001,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {2.00, 2},
       "the NC sets reserved SCW bit 20 for 5 cycles",
       [](FaultActions& f) { f.nc(0, NcAction::ReservedBit, 5); }},
      {RuleId::Rdy001,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {2.45, 2},
       "the drive inverts ServoRDY for 50 ms",
       [](FaultActions& f) { f.quirk(DriveQuirk::ReadyInverted); }},
      {RuleId::Flt001,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {1.50, 0},
       "a drive fault (E09) while enabled; the drive stays enabled 200 ms",
       [](FaultActions& f) {
         f.driveFault();
         f.quirk(DriveQuirk::SlowFaultReaction);
       }},
      {RuleId::Pt001,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {2.45, 1},
       "the NC selects table 8; the drive follows only after 120 ms",
       [](FaultActions& f) {
         f.nc(0, NcAction::Table, 8);
         f.quirk(DriveQuirk::IgnoreTable);
       }},
      {RuleId::Msg001,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {2.00, 0},
       "the drive sends message code 7 for one cycle",
       [](FaultActions& f) { f.quirk(DriveQuirk::UndefinedMessage); }},
      {RuleId::Com001,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {},
       {2.90, 0},
       "the axis's slave does not process one cycle's LRW (WKC 3 short)",
       [](FaultActions& f) { f.bus({Bus::SkipAxisLrw}); }},
      {RuleId::Com002,
       FaultPhase::Cycle,
       AxisNeed::None,
       {},
       {3.20, -1},
       "the master sends nothing for 2 cycles",
       [](FaultActions& f) {
         f.bus({Bus::SkipCycles, 2});
       }},
      {RuleId::Com003,
       FaultPhase::Cycle,
       AxisNeed::Any,
       {RuleId::Com004},
       {3.40, 2},
       "3 cycles are lost before the slaves; the axis's drive raises no ECatTErr",
       [](FaultActions& f) {
         f.quirk(DriveQuirk::SilentTimeout);
         f.bus({Bus::LoseBeforeSlaves, 3});
       }},
      {RuleId::Com004,
       FaultPhase::Cycle,
       AxisNeed::None,
       {},
       {3.05, -1},
       "one cycle's frame is lost after the slaves",
       [](FaultActions& f) { f.bus({Bus::LoseAfterSlaves}); }},
      {RuleId::Com005,
       FaultPhase::Cycle,
       AxisNeed::None,
       {RuleId::Com004},
       {3.80, -1},
       "4 cycles are lost before the slaves (the drives raise ECatTErr)",
       [](FaultActions& f) {
         f.bus({Bus::LoseBeforeSlaves, 4});
       }},
      {RuleId::Com006,
       FaultPhase::Cycle,
       AxisNeed::None,
       {},
       {3.60, -1},
       "the master sends 6 cycles alternately a quarter cycle late and on time",
       [](FaultActions& f) {
         f.bus({Bus::JitterCycles, 6});
       }},
      {RuleId::Com007,
       FaultPhase::Cycle,
       AxisNeed::None,
       {},
       {3.70, -1},
       "one cycle's frame comes back three quarters of a cycle late",
       [](FaultActions& f) { f.bus({Bus::LateReturn}); }},
      {RuleId::Esm001,
       FaultPhase::Startup,
       AxisNeed::Any,
       {RuleId::Esm003},
       kInStartup(0),
       "the master requests OP from PRE-OP of the axis's slave (refused with 0x0011)",
       [](FaultActions& f) { f.startup(StartupFault::RequestOpFromPreOp); }},
      {RuleId::Esm002,
       FaultPhase::Startup,
       AxisNeed::Any,
       {},
       kInStartup(1),
       "the NC sends SE 0x1 to the axis while its slave is in SAFE-OP",
       [](FaultActions& f) { f.startup(StartupFault::EnableBeforeOp); }},
      {RuleId::Esm003,
       FaultPhase::Startup,
       AxisNeed::Any,
       {},
       kInStartup(2),
       "the axis's slave refuses SAFE-OP -> OP once (0x001D)",
       [](FaultActions& f) { f.startup(StartupFault::RefuseOp); }},
      {RuleId::Esm004,
       FaultPhase::Startup,
       AxisNeed::Any,
       {},
       kInStartup(3),
       "the axis's slave powers up with an AL error (0x0050) that the master acknowledges",
       [](FaultActions& f) { f.startup(StartupFault::PowerUpError); }},
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
