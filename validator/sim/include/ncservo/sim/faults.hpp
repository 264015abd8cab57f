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

// What a recipe can do, at the fault's time and on its axis.
class FaultActions {
 public:
  // The NC of the axis does `action` `offset_ns` after the fault's time.
  virtual void nc(std::int64_t offset_ns, NcAction action, double value = 0) = 0;
  virtual void quirk(DriveQuirk quirk) = 0;  // armed in the axis's drive
  virtual void driveFault() = 0;             // E09 (following error) in the axis's drive
  virtual void bus(BusFault fault) = 0;
  virtual void startup(StartupFault fault) = 0;

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
