// The two ends of the simulated link, stepped once per cycle: a drive that answers as
// docs/protocol.md §1–7 say, and an NC axis that commands a commissioning session. Both are pure
// functions of their inputs, their seed and the misbehaviours armed in them (the simulator's
// faults), so tests can drive them step by step. No EtherCAT here: the bus is simulator.hpp.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/pdo.hpp"
#include "ncservo/protocol/word_bits.hpp"

namespace ncservo::sim {

inline constexpr std::int64_t kUs = 1000;
inline constexpr std::int64_t kMs = 1'000'000;
inline constexpr std::int64_t kSecond = 1'000'000'000;

// SplitMix64: a seeded generator whose output is the same on every platform (the standard
// library's distributions are not), so a capture is a pure function of the options.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  // [lo, hi], both inclusive
  std::int64_t between(std::int64_t lo, std::int64_t hi) {
    return lo + static_cast<std::int64_t>(next() % static_cast<std::uint64_t>(hi - lo + 1));
  }

 private:
  std::uint64_t state_;
};

// The PDO values of docs/protocol.md §1.
struct RxPdo {
  std::int32_t ssp = 0;
  std::uint32_t scw = 0;
  std::int16_t ext_code = 0;
};
struct TxPdo {
  std::int64_t actpos = 0;
  std::uint32_t ssw = 0;
  std::uint32_t sew = 0;
  std::int32_t msg_code = 0;
  float msg_data = 0;
  std::array<float, 4> ext_data{};
};
// The words of the PDOs, as writePdo writes them and readPdo reads them (pdo.hpp).
PdoValues pdoValues(const RxPdo& pdo);
PdoValues pdoValues(const TxPdo& pdo);
RxPdo rxPdoOf(const PdoValues& values);
TxPdo txPdoOf(const PdoValues& values);
void encodeRx(const RxPdo& pdo, std::uint8_t* out);  // kRxPdoSize bytes
void encodeTx(const TxPdo& pdo, std::uint8_t* out);  // kTxPdoSize bytes
RxPdo decodeRx(const std::uint8_t* in);              // kRxPdoSize bytes

// The bits themselves are the protocol's (word_bits.hpp); these are the simulator's helpers over
// them.
namespace bits {
using namespace ncservo::bits;
// The other bits the simulator's drives raise or show (docs/protocol.md §3-4).
inline constexpr std::uint32_t kTempWarning = mask32("ncservo.ssw.temp_warning");
inline constexpr std::uint32_t kEncoderErr = mask32("ncservo.sew.encoder");
inline constexpr std::uint32_t kI2tEndat = mask32("ncservo.sew.i2t_endat");
inline constexpr std::uint32_t kBusVoltageErr = mask32("ncservo.sew.bus_voltage");
inline constexpr std::uint32_t kCurrentErr = mask32("ncservo.sew.current");
inline constexpr std::uint32_t kServoRuntime = mask32("ncservo.sew.servo_runtime");
inline constexpr std::uint32_t kPdpint = mask32("ncservo.sew.pdpint");
inline constexpr std::uint32_t kParamChecksum = mask32("ncservo.sew.param_checksum");
inline constexpr std::uint32_t kEcatWatchdog = mask32("ncservo.sew.ecat_watchdog");
inline constexpr std::uint32_t kOverspeed = mask32("ncservo.sew.overspeed");

// Parameter table number 1..8 <-> the SCW/SSW bits (table = ExtPRMTBL·4 + PRMTBL + 1).
std::uint32_t scwTable(int table);
std::uint32_t sswTable(int table);
int tableOfScw(std::uint32_t scw);
}  // namespace bits

inline constexpr double kSspPerRpm = 100.0;  // SSP unit: 0.01 rpm (this simulator's choice)

// How a simulated drive breaks the protocol (each one makes one rule of docs/rules.md fire).
// A misbehaviour is armed from a time on and applies to the first occasion after it.
enum class DriveQuirk : std::uint8_t {
  SpuriousEnable,       // SE-002: ServoEn rises for a moment without a valid enable
  LateDisable,          // SE-003: stays enabled long after the enable ended
  IgnoreEnable,         // SE-004: does not enable although ready
  HoldZPulseAck,        // ZP-001: keeps ZPulseAck after the request fell
  SpuriousZPulseAck,    // ZP-002: ZPulseAck pulse with no request
  SpuriousClearAck,     // EC-001: ErrClearAck pulse with no ErrorClear
  HoldClearAck,         // EC-003: keeps ErrClearAck after ErrorClear fell
  IgnoreClear,          // EC-004: does not acknowledge an error clear
  CauseWithoutSummary,  // SEW-001: a cause bit with SEW bit 0 clear
  SummaryWithoutCause,  // SEW-002: SEW bit 0 with no cause
  ReservedErrorBit,     // SEW-003: a reserved SEW bit
  ReservedStatusBit,    // SSW-001: a reserved SSW bit
  ReadyInverted,        // RDY-001: ServoRDY against the Servo_Ready_Mode table
  SlowFaultReaction,    // FLT-001: stays enabled with an error
  IgnoreTable,          // PT-001: does not follow a parameter table change
  UndefinedMessage,     // MSG-001: message code 7
  SilentTimeout,        // COM-003: no ECatTErr after lost cycles
};

// A quantity the drive reports that climbs (docs/simulate.md, the incidents scenario) until it
// trips the drive's fault, then settles back.
struct Drift {
  enum class Quantity : std::uint8_t {
    MotorTemperature,  // message code 4 and extra data 4; SSW.TempWarning above 80 °C
    BusVoltage,        // message code 3
    MotorCurrent,      // message codes 1 and 2, extra data 3 (reported only: no heat)
  };
  Quantity quantity = Quantity::MotorTemperature;
  std::int64_t from_ns = 0;
  double per_second = 0;    // the climb
  double trip = 0;          // the value at which the drive faults
  std::uint32_t cause = 0;  // the SEW cause bit it raises then
};

struct DriveSetup {
  int axis = 0;
  bool incremental = false;  // incremental encoder (zero-pulse search), else absolute
  int ready_mode = 0;        // Servo_Ready_Mode (docs/protocol.md §5)
  std::uint64_t seed = 1;
};

class DriveModel {
 public:
  static constexpr std::int64_t kIncrementalCountsPerRev = 10000;  // 2500 lines, x4
  static constexpr std::int64_t kAbsoluteCountsPerRev = 1 << 20;   // 20-bit single turn

  explicit DriveModel(const DriveSetup& setup);

  // One cycle: the outputs the drive took (nullptr when the cycle's frame did not reach it)
  // and the time. The result is what it writes into the next frame.
  void step(const RxPdo* outputs, std::int64_t now_ns);
  const TxPdo& inputs() const { return inputs_; }
  // Outputs are ignored outside OP (the slave is in SAFE-OP: inputs only).
  void setOperational(bool op) { operational_ = op; }
  // A drive fault: the cause bit rises now (orderly reaction follows).
  void raiseFault(std::uint32_t cause_bit) { pending_faults_ |= cause_bit; }
  void arm(DriveQuirk quirk, std::int64_t from_ns);
  // A quantity that climbs from its time until it trips a fault (one at a time).
  void drift(const Drift& drift) { drift_ = drift; }

  bool enabled() const { return enabled_; }
  double speedRpm() const { return speed_rpm_; }

 private:
  struct Armed {
    DriveQuirk quirk;
    std::int64_t from_ns;
    std::int64_t until_ns = -1;  // set when it takes effect; -1 while waiting
    bool done = false;
  };
  Armed* active(DriveQuirk quirk, std::int64_t now_ns);                   // armed and due
  bool fire(DriveQuirk quirk, std::int64_t now_ns, std::int64_t for_ns);  // starts a window
  bool within(DriveQuirk quirk, std::int64_t now_ns);                     // inside a started window
  void updateEnable(const RxPdo& rx, std::int64_t now_ns);
  void updateHandshakes(const RxPdo& rx, std::int64_t now_ns);
  void updateMotion(const RxPdo& rx, double dt);
  void buildInputs(const RxPdo& rx, std::int64_t now_ns);
  void updateDrift(std::int64_t now_ns, double dt);

  DriveSetup setup_;
  Rng rng_;
  std::vector<Armed> quirks_;
  bool operational_ = true;
  std::int64_t last_ns_ = -1;
  RxPdo last_rx_{0, bits::kEmgon | bits::kBrake, 0};  // outputs last taken
  std::uint64_t cycle_ = 0;
  // enable (docs/protocol.md §2)
  std::uint32_t last_se_ = 0;
  bool valid_enable_ = false;
  bool enabled_ = false;
  std::int64_t last_enable_end_ns_ = 0;  // last time a valid enable was seen
  std::int64_t want_since_ns_ = -1;      // enable wanted (valid, ready) since
  std::int64_t enable_after_ns_ = 0;
  std::int64_t unwant_since_ns_ = -1;  // valid enable gone since
  std::int64_t disable_after_ns_ = 0;
  std::int64_t reaction_ns_ = -1;  // this fault's reaction time
  std::int64_t spurious_until_ns_ = -1;
  std::int64_t enable_delay_ns_;
  std::int64_t disable_delay_ns_;
  std::int64_t fault_reaction_ns_;
  // errors (docs/protocol.md §4, §7)
  std::uint32_t causes_ = 0;          // latched cause bits
  std::uint32_t pending_faults_ = 0;  // raised, latched at the next step
  std::int64_t fault_since_ns_ = -1;
  int missed_cycles_ = 0;
  // zero-pulse handshake
  bool zp_ack_ = false;
  bool zp_searching_ = false;
  std::int64_t zp_release_ns_ = -1;       // request fell: the ack drops at this time
  std::int64_t zp_request_since_ns_ = 0;  // last time the request was seen
  std::int64_t zp_spurious_until_ns_ = -1;
  std::optional<std::int32_t> zero_pulse_;  // position latched at the last zero pulse
  // error-clear handshake
  bool clear_ack_ = false;
  std::int64_t clear_since_ns_ = -1;  // ErrorClear seen since
  std::int64_t clear_after_ns_ = 0;
  std::int64_t clear_release_ns_ = -1;
  std::int64_t clear_request_since_ns_ = 0;  // last time ErrorClear was seen
  std::int64_t clear_spurious_until_ns_ = -1;
  // parameter table
  int table_ = 1;
  int table_target_ = 1;
  std::int64_t table_since_ns_ = -1;
  std::int64_t table_after_ns_ = 0;
  std::int64_t table_delay_ns_;
  // motion
  double speed_rpm_ = 0;
  double position_ = 0;  // encoder counts
  double accel_ = 0;     // rpm/s, for the current
  double current_a_ = 0;
  double temperature_c_ = 35.0;
  // the drift under way (the incidents scenario), and what it adds to the reported values
  std::optional<Drift> drift_;
  bool drift_tripped_ = false;
  double extra_bus_v_ = 0;
  double extra_current_a_ = 0;
  TxPdo inputs_;
};

// What the NC's plan asks of one axis at a time (the scenario).
enum class NcAction : std::uint8_t {
  Enable,     // SE 0x0 -> 0x1 -> 0x2, wait for ServoEn
  Disable,    // SE 0x2 -> 0x1 -> 0x0
  Speed,      // new speed target (value: rpm)
  SpeedStep,  // new speed target (value: rpm), set at once instead of ramped
  ZeroPulse,  // zero-pulse search (incremental encoder)
  Table,      // parameter table (value: 1..8)
  Emergency,  // EMGON 0 for value milliseconds, speed to zero
  // misbehaviours of the NC (each makes one rule of docs/rules.md fire)
  IllegalEnable,      // SE-001: SE 0x0 -> 0x2
  ZeroPulseAbsolute,  // ZP-003: ZPulseRequest on an absolute axis (value: ms)
  HoldErrorClear,     // EC-002: the next ErrorClear is held value ms after ErrClearAck
  ReservedBit,        // SCW-001: SCW bit 20 for value cycles
};

struct NcEvent {
  std::int64_t at_ns;
  NcAction action;
  double value = 0;
};

class NcAxis {
 public:
  explicit NcAxis(bool incremental);
  // Events in any order; they run at the first cycle at or after their time.
  void schedule(const NcEvent& event);
  // One cycle: the latest inputs the NC received (nullptr: none yet or not valid), the time.
  RxPdo step(const TxPdo* inputs, std::int64_t now_ns);
  // Outside OP the NC sends neutral outputs (SE 0), unless told to misbehave (ESM-002).
  void setOperational(bool op) { operational_ = op; }
  void setEnableBeforeOp(bool on) { enable_before_op_ = on; }
  // The axis's slave fell out of OP (the master read it): neutral outputs until setOperational,
  // then a legal enable again if the plan wants the axis on.
  void fellFromOp();
  std::size_t pendingEvents() const { return events_.size(); }

 private:
  enum class Phase : std::uint8_t {
    Off,
    Prepare,   // SE 0x1 before 0x2
    Enabling,  // SE 0x2, waiting for ServoEn
    On,
    FaultWait,  // drive reports an error: SE held until the drive is off
    Clearing,   // ErrorClear 1 until ErrClearAck
    Releasing,  // ErrorClear 0 until ErrClearAck falls
    Disabling,  // SE 0x1, then 0x0
  };
  void runEvents(std::int64_t now_ns);
  void enter(Phase phase, std::int64_t now_ns);
  void followDrive(const TxPdo& inputs, std::int64_t now_ns);
  // This cycle's set point and control word; `dt` seconds since the last cycle.
  RxPdo outputs(std::int64_t now_ns, double dt);

  bool incremental_;
  std::vector<NcEvent> events_;  // sorted by time, newest last
  Phase phase_ = Phase::Off;
  std::int64_t phase_since_ns_ = 0;
  int phase_cycles_ = 0;
  std::int64_t last_ns_ = -1;
  bool operational_ = true;
  bool enable_before_op_ = false;
  bool want_on_ = false;  // the plan wants the axis enabled
  std::uint32_t se_ = 0;
  bool emgon_ = true;
  std::int64_t emergency_until_ns_ = -1;
  double target_rpm_ = 0;
  double ssp_rpm_ = 0;  // ramped set point
  int table_ = 1;
  bool zp_request_ = false;
  std::int64_t zp_since_ns_ = -1;
  std::int64_t zp_abs_until_ns_ = -1;
  bool error_clear_ = false;
  std::int64_t hold_clear_ns_ = 0;  // EC-002 misbehaviour: hold ErrorClear this long
  std::int64_t ack_seen_ns_ = -1;
  int reserved_cycles_ = 0;
};

}  // namespace ncservo::sim
