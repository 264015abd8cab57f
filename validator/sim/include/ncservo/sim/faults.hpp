// The simulator's fault recipes: for each rule of docs/rules.md, what the simulator does to make it
// fire (`ncservo simulate --fault`, --list-faults) and where the `faults` scenario does it. One
// row per rule of kRules (a unit test checks), or a row that says why the rule is not injectable.
#pragma once

#include <cstdint>
#include <vector>

#include "ncservo/rules/rules.hpp"
#include "ncservo/sim/models.hpp"

namespace ncservo::sim {

enum class FaultPhase : std::uint8_t {
  Cycle,    // during the cyclic exchange, at a time the user may give
  Startup,  // in the master's start-up
};
enum class AxisNeed : std::uint8_t { Any, Incremental, Absolute, None };

// A fault of the bus, started at the fault's time.
struct BusFault {
  enum class Kind : std::uint8_t {
    SkipAxisLrw,       // the axis's slave does not process one cycle's LRW
    SkipCycles,        // the master sends nothing for `cycles` cycles
    LoseBeforeSlaves,  // `cycles` cycles' frames are lost before the slaves
    LoseAfterSlaves,   // one cycle's frame is lost after the slaves
    JitterCycles,      // `cycles` cycles sent alternately a quarter cycle late and on time
    LateReturn,        // one cycle's last frame comes back three quarters of a cycle late
  };
  Kind kind;
  int cycles = 1;
};

// A fault of the master's start-up, on the axis's slave.
enum class StartupFault : std::uint8_t {
  RequestOpFromPreOp,  // the master's first SAFE-OP request asks for OP
  EnableBeforeOp,      // the NC sends SE 0x1 while the slave is in SAFE-OP
  RefuseOp,            // the slave refuses SAFE-OP -> OP once
  PowerUpError,        // the slave powers up with an AL error
};

// How a drive's mailbox breaks what the rules expect (docs/simulate.md#diagnosis).
enum class MailboxQuirk : std::uint8_t {
  EmergencyWithoutFault,  // an emergency 0x8611 with no cause bit rising (MBX-001)
  ErrorResetNow,          // an error reset emergency now, the drive's first word (MBX-002)
  SilentFault,            // the next fault without an emergency (MBX-002)
  WrongHistoryCode,       // the next history entry carries 0x1000, not the cause's code (ERH-002)
  LoseHistory,            // the history loses its entries (ERH-001)
};

// What the master, the NC and the slaves say besides the process data, at a time after the
// fault's (--diagnosis; each recipe that does one needs it).
struct DiagnosisFault {
  enum class Kind : std::uint8_t {
    Mailbox,         // `quirk` in the axis's drive's mailbox
    NcRead,          // the NC reads `index`:`subindex` of the axis's drive
    CorruptFrames,   // the cable into the axis's slave's port 0 corrupts `amount` frames
    LinkDown,        // that cable goes down and up between two frames (lost links at both ends)
    TimeDifference,  // the axis's slave's system time difference is `amount` ns for `for_ns`
  };
  Kind kind;
  std::int64_t offset_ns = 0;
  MailboxQuirk quirk = MailboxQuirk::EmergencyWithoutFault;
  std::uint16_t index = 0;
  std::uint8_t subindex = 0;
  std::int32_t amount = 0;
  std::int64_t for_ns = 0;
};

// What a recipe can do, at the fault's time and on its axis.
class FaultActions {
 public:
  // The NC of the axis does `action` `offset_ns` after the fault's time.
  virtual void nc(std::int64_t offset_ns, NcAction action, double value = 0) = 0;
  virtual void quirk(DriveQuirk quirk) = 0;  // armed in the axis's drive
  virtual void driveFault() = 0;             // E09 (following error) in the axis's drive
  virtual void bus(BusFault fault) = 0;
  virtual void startup(StartupFault fault) = 0;
  virtual void diagnosis(const DiagnosisFault& fault) = 0;

 protected:
  ~FaultActions() = default;
};

// Where the `faults` scenario puts a rule's fault.
struct ScenarioSlot {
  double at_s = 0;  // capture time (a start-up fault: unused)
  int axis = -1;    // -1: the whole bus
};

struct FaultRecipe {
  RuleId rule;
  FaultPhase phase;
  AxisNeed need;
  std::vector<RuleId> companions;  // other rules the fault fires as well (captures/README.md)
  ScenarioSlot scenario;
  const char* description;  // what --list-faults prints: what the simulator does, or why not
  void (*apply)(FaultActions& actions);  // nullptr: the rule is not injectable
  // How long the fault's condition stands from its time, so that a capture can begin inside it
  // (--start-in fault:RULE, docs/simulate.md#shapes); 0: it has no condition to begin inside
  // from its time (a moment, or one that comes later).
  std::int64_t standing_ns = 0;
  // It needs the mailboxes and the master's polls of --diagnosis (turned on with it).
  bool diagnosis = false;
  bool injectable() const { return apply != nullptr; }
};

const std::vector<FaultRecipe>& faultRecipes();
// The rule's row; nullptr if the table has none.
const FaultRecipe* faultRecipe(RuleId rule);

// Other rules a fault necessarily fires as well.
std::vector<RuleId> companionsOf(RuleId rule);
// One line: what the simulator does to make the rule fire, or why it cannot.
const char* faultDescription(RuleId rule);

}  // namespace ncservo::sim
