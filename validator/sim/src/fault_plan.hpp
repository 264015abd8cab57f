// The faults of one run in time: the recipes (faults.hpp) applied to the segment, the drives and
// the NCs, and the bus faults and drive faults waiting for their time.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "ncservo/sim/faults.hpp"
#include "ncservo/sim/models.hpp"
#include "segment.hpp"

namespace ncservo::sim {

class FaultPlan final : public FaultActions {
 public:
  FaultPlan(Segment& segment, std::vector<DriveModel>& drives, std::vector<NcAxis>& ncs)
      : segment_(segment), drives_(drives), ncs_(ncs) {}

  // The rule's recipe at `at_s` seconds of capture time (a start-up fault: unused) on an axis
  // (-1: the whole bus).
  void inject(RuleId rule, double at_s, int axis);
  // Every injectable rule where the `faults` scenario puts it (those of --diagnosis with it).
  void injectScenario(bool diagnosis);
  // A drive fault of a scenario's plan (not a rule's fault).
  void scheduleDriveFault(std::int64_t at_ns, int axis, std::uint32_t cause);
  // A bus fault of a scenario's plan, on an axis (-1: the whole bus).
  void scheduleBusFault(std::int64_t at_ns, int axis, BusFault fault);

  // Once per cycle, before it: raises the drive faults and starts the bus faults now due.
  void raiseDriveFaults(std::int64_t now_ns);
  void dropRaisedDriveFaults();
  void startBusFaults(std::int64_t now_ns);
  // What this cycle's frames suffer; each call takes one cycle's share.
  bool takeSkippedCycle();
  bool takeLossBeforeSlaves();
  bool takeLossAfterSlaves();
  // How late this cycle is sent (COM-006), and how late its last frame comes back (COM-007),
  // in cycles.
  double takeSendDelayCycles();
  double takeReturnDelayCycles();

  std::optional<std::size_t> opRequestSlave() const { return op_request_slave_; }
  // The diagnosis faults, each with its axis and time; the simulator marks them done.
  struct TimedDiagnosis {
    DiagnosisFault fault;
    int axis;
    std::int64_t at_ns;
    bool done = false;
  };
  std::vector<TimedDiagnosis>& diagnosisFaults() { return diagnosis_faults_; }

  // Each fault as the plan placed it: the rule, its axis (-1: the whole bus), its time and
  // whether it is the start-up's.
  struct Placed {
    RuleId rule;
    int axis;
    std::int64_t at_ns;
    bool startup;
    // The other axes its findings name (none: a slave no axis names): a link down is counted at
    // both its ends.
    std::vector<std::optional<int>> also = {};
  };
  const std::vector<Placed>& placed() const { return placed_; }

 private:
  void nc(std::int64_t offset_ns, NcAction action, double value) override;
  void quirk(DriveQuirk quirk) override;
  void driveFault() override;
  void bus(BusFault fault) override;
  void startup(StartupFault fault) override;
  void diagnosis(const DiagnosisFault& fault) override;

  struct TimedBusFault {
    BusFault fault;
    std::int64_t at_ns;
    int axis;
    bool done = false;
  };
  struct DriveFaultEvent {
    std::int64_t at_ns;
    int axis;
    std::uint32_t cause;
    bool done = false;
  };

  Segment& segment_;
  std::vector<DriveModel>& drives_;
  std::vector<NcAxis>& ncs_;
  // the recipe being applied
  std::int64_t at_ns_ = 0;
  int axis_ = -1;
  std::size_t axisIndex() const { return static_cast<std::size_t>(axis_ < 0 ? 0 : axis_); }

  std::vector<Placed> placed_;
  std::vector<TimedBusFault> bus_faults_;
  std::vector<DriveFaultEvent> drive_faults_;
  std::vector<TimedDiagnosis> diagnosis_faults_;
  int skip_cycles_ = 0;                          // COM-002
  int lose_before_slaves_ = 0;                   // COM-003, COM-005
  bool lose_after_slaves_ = false;               // COM-004
  int jitter_cycles_ = 0;                        // COM-006
  bool late_return_ = false;                     // COM-007
  std::optional<std::size_t> op_request_slave_;  // ESM-001
};

}  // namespace ncservo::sim
