#include "fault_plan.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace ncservo::sim {

void FaultPlan::inject(RuleId rule, double at_s, int axis) {
  const FaultRecipe* recipe = faultRecipe(rule);
  if (recipe == nullptr || !recipe->injectable()) return;  // refused by resolveOptions
  at_ns_ = static_cast<std::int64_t>(std::llround(at_s * 1e9));
  axis_ = axis;
  placed_.push_back({rule, axis, at_ns_, recipe->phase == FaultPhase::Startup});
  recipe->apply(*this);
}

void FaultPlan::injectScenario(bool diagnosis) {
  // A rule off by default would not be reported by a plain `validate` of the scenario.
  for (const FaultRecipe& recipe : faultRecipes()) {
    if (recipe.injectable() && ruleDef(recipe.rule).by_default == ByDefault::On &&
        (diagnosis || !recipe.diagnosis)) {
      inject(recipe.rule, recipe.scenario.at_s, recipe.scenario.axis);
    }
  }
}

void FaultPlan::scheduleDriveFault(std::int64_t at_ns, int axis, std::uint32_t cause) {
  drive_faults_.push_back({at_ns, axis, cause});
}

void FaultPlan::scheduleBusFault(std::int64_t at_ns, int axis, BusFault fault) {
  bus_faults_.push_back({fault, at_ns, axis});
}

void FaultPlan::nc(std::int64_t offset_ns, NcAction action, double value) {
  ncs_[axisIndex()].schedule({at_ns_ + offset_ns, action, value});
}
void FaultPlan::quirk(DriveQuirk quirk) {
  drives_[axisIndex()].arm(quirk, at_ns_);
}
void FaultPlan::driveFault() {
  scheduleDriveFault(at_ns_, axis_, bits::kFollowing);
}
void FaultPlan::bus(BusFault fault) {
  bus_faults_.push_back({fault, at_ns_, axis_});
}
void FaultPlan::diagnosis(const DiagnosisFault& fault) {
  diagnosis_faults_.push_back({fault, axis_, at_ns_ + fault.offset_ns});
  // A link down is counted at port 1 of the slave before too, when there is one.
  const auto position = static_cast<std::size_t>(segment_.servo_slave[axisIndex()]);
  if (fault.kind == DiagnosisFault::Kind::LinkDown && position > 0) {
    const int before = segment_.escs[position - 1].axis;
    placed_.back().also.push_back(before < 0 ? std::nullopt : std::optional<int>(before));
  }
}
void FaultPlan::startup(StartupFault fault) {
  const auto slave = static_cast<std::size_t>(segment_.servo_slave[axisIndex()]);
  switch (fault) {
    case StartupFault::RequestOpFromPreOp:
      op_request_slave_ = slave;
      break;
    case StartupFault::EnableBeforeOp:
      ncs_[axisIndex()].setEnableBeforeOp(true);
      break;
    case StartupFault::RefuseOp:
      segment_.escs[slave].refuse_next_op = true;
      break;
    case StartupFault::PowerUpError:
      segment_.escs[slave].powerUpError();
      break;
  }
}

void FaultPlan::raiseDriveFaults(std::int64_t now_ns) {
  for (DriveFaultEvent& e : drive_faults_) {
    if (!e.done && now_ns >= e.at_ns) {
      drives_[static_cast<std::size_t>(e.axis)].raiseFault(e.cause);
      e.done = true;
    }
  }
}
void FaultPlan::dropRaisedDriveFaults() {
  drive_faults_.erase(std::remove_if(drive_faults_.begin(), drive_faults_.end(),
                                     [](const DriveFaultEvent& e) { return e.done; }),
                      drive_faults_.end());
}

void FaultPlan::startBusFaults(std::int64_t now_ns) {
  for (TimedBusFault& f : bus_faults_) {
    if (f.done || now_ns < f.at_ns) continue;
    f.done = true;
    switch (f.fault.kind) {
      case BusFault::Kind::SkipAxisLrw:
        segment_.servo(f.axis).skip_next_lrw = true;
        break;
      case BusFault::Kind::SkipCycles:
        skip_cycles_ = f.fault.cycles;
        break;
      case BusFault::Kind::LoseBeforeSlaves:
        lose_before_slaves_ = f.fault.cycles;
        break;
      case BusFault::Kind::LoseAfterSlaves:
        lose_after_slaves_ = true;
        break;
      case BusFault::Kind::JitterCycles:
        jitter_cycles_ = f.fault.cycles;
        break;
      case BusFault::Kind::LateReturn:
        late_return_ = true;
        break;
    }
  }
}

bool FaultPlan::takeSkippedCycle() {
  if (skip_cycles_ == 0) return false;
  --skip_cycles_;
  return true;
}
bool FaultPlan::takeLossBeforeSlaves() {
  if (lose_before_slaves_ == 0) return false;
  --lose_before_slaves_;
  return true;
}
bool FaultPlan::takeLossAfterSlaves() {
  return std::exchange(lose_after_slaves_, false);
}
// Intervals of 1.25 and 0.75 cycles: a quarter off nominal, under COM-002's 1.5.
double FaultPlan::takeSendDelayCycles() {
  if (jitter_cycles_ == 0) return 0;
  return (jitter_cycles_--) % 2 == 0 ? 0.25 : 0.0;
}
// Back before the next cycle's master frame (no COM-004).
double FaultPlan::takeReturnDelayCycles() {
  return std::exchange(late_return_, false) ? 0.75 : 0.0;
}

}  // namespace ncservo::sim
