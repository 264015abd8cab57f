// The simulated EtherCAT segment (simulator.hpp): ESC models, the master's start-up and cycle,
// the scenarios, and the faults that make each rule of RULES.md fire.
#include "ncservo/simulator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <sstream>
#include <utility>

#include "ncservo/al_tracker.hpp"
#include "ncservo/config.hpp"
#include "ncservo/eni.hpp"
#include "ncservo/ethercat.hpp"
#include "ncservo/pdo_layout.hpp"
#include "ncservo/sim_models.hpp"

namespace ncservo::sim {
namespace {

constexpr std::int64_t kUs = 1000;
constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kSecond = 1'000'000'000;
constexpr std::int64_t kEpochNs = 1'767'225'600 * kSecond;  // 2026-01-01 00:00:00 UTC

// ESC registers (PROTOCOL.md §8)
constexpr std::uint16_t kRegType = 0x0000;
using ecat::kRegAlControl;
using ecat::kRegAlStatus;
using ecat::kRegAlStatusCode;
constexpr std::uint16_t kRegStation = ecat::kRegStationAddress;
constexpr std::uint16_t kRegFmmu = ecat::kRegFmmu0;
constexpr std::uint16_t kRegSyncManager = ecat::kRegSyncManager0;
constexpr std::uint16_t kRegSystemTime = ecat::kRegDcSystemTime;
constexpr std::size_t kFmmuSize = ecat::kFmmuStride;
constexpr std::size_t kSyncManagerSize = ecat::kSyncManagerStride;
constexpr std::size_t kEscMemory = 0x2000;  // registers and process RAM
constexpr std::uint16_t kFirstStation = 0x03E9;

constexpr std::uint8_t kInit = 1, kPreOp = 2, kSafeOp = 4, kOp = 8;
constexpr std::uint8_t kAlErrorBit = 0x10;
constexpr std::uint16_t kCodeInvalidTransition = 0x0011;  // invalid requested state change
constexpr std::uint16_t kCodeInvalidOutputs = 0x001D;     // invalid output configuration
constexpr std::uint16_t kCodePowerUp = 0x0050;            // EEPROM no access (left from power-up)

// Process RAM of the slaves (their SM2/SM3, or SM0 of the digital terminals).
constexpr std::uint16_t kServoRxPhys = 0x1100;
constexpr std::uint16_t kServoTxPhys = 0x1180;
constexpr std::uint16_t kOutTerminalPhys = 0x0F00;
constexpr std::uint16_t kInTerminalPhys = 0x1000;
constexpr std::uint32_t kLogicalBase = 0x00010000;
constexpr std::uint32_t kLogicalFrameStride = 0x1000;
constexpr std::size_t kMaxLrwData = 1450;  // 29 axes of 50 bytes (PROTOCOL.md §9.4)
constexpr int kMaxServosPerFrame = 29;

constexpr std::array<std::uint8_t, 6> kBroadcastMac = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
constexpr std::array<std::uint8_t, 6> kMasterMac = {0x00, 0x1B, 0x21, 0x4E, 0x43, 0x01};
constexpr std::uint8_t kLocallyAdministered = 0x02;
constexpr std::size_t kMinFrame = 60;

constexpr double kStartupSeconds = 0.2;  // the NC's plan starts once the start-up is over

// --- the fault catalogue: one row per rule ---

enum class FaultKind : std::uint8_t { Nc, Drive, Bus, Startup };
enum class AxisNeed : std::uint8_t { Any, Incremental, Absolute, None };

struct FaultRecipe {
  RuleId rule;
  FaultKind kind;
  AxisNeed need;
  std::vector<RuleId> companions;
  const char* description;
};

const std::vector<FaultRecipe>& recipes() {
  static const std::vector<FaultRecipe> table = {
      {RuleId::Se001,
       FaultKind::Nc,
       AxisNeed::Any,
       {},
       "the NC disables the axis, then enables it with SE 0x0 -> 0x2 (and later legally)"},
      {RuleId::Se002,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "the drive shows ServoEn for 4 ms while the axis is disabled"},
      {RuleId::Se003,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "the drive stays enabled 60 ms after the NC disables the axis"},
      {RuleId::Se004,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "the drive takes 160 ms to follow a legal enable"},
      {RuleId::Zp001,
       FaultKind::Drive,
       AxisNeed::Incremental,
       {},
       "the drive keeps ZPulseAck 60 ms after the request falls"},
      {RuleId::Zp002,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "the drive shows ZPulseAck for 4 ms with no request"},
      {RuleId::Zp003,
       FaultKind::Nc,
       AxisNeed::Absolute,
       {},
       "the NC requests a zero-pulse search for 30 ms on an absolute axis"},
      {RuleId::Ec001,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "the drive shows ErrClearAck for 4 ms with no ErrorClear"},
      {RuleId::Ec002,
       FaultKind::Nc,
       AxisNeed::Any,
       {},
       "a drive fault (E09); the NC holds ErrorClear 100 ms after ErrClearAck"},
      {RuleId::Ec003,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "a drive fault (E09); the drive keeps ErrClearAck 60 ms after ErrorClear falls"},
      {RuleId::Ec004,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "a drive fault (E09); the drive answers ErrorClear only after 160 ms"},
      {RuleId::Sew001,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "the drive shows OverLoad for one cycle without the summary bit"},
      {RuleId::Sew002,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "the drive shows the summary bit without a cause for 50 ms"},
      {RuleId::Sew003,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "the drive sets reserved SEW bit 25 for one cycle"},
      {RuleId::Ssw001,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "the drive sets reserved SSW bit 13 for one cycle"},
      {RuleId::Scw001,
       FaultKind::Nc,
       AxisNeed::Any,
       {},
       "the NC sets reserved SCW bit 20 for 5 cycles"},
      {RuleId::Rdy001, FaultKind::Drive, AxisNeed::Any, {}, "the drive inverts ServoRDY for 50 ms"},
      {RuleId::Flt001,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "a drive fault (E09) while enabled; the drive stays enabled 200 ms"},
      {RuleId::Pt001,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "the NC selects table 8; the drive follows only after 120 ms"},
      {RuleId::Msg001,
       FaultKind::Drive,
       AxisNeed::Any,
       {},
       "the drive sends message code 7 for one cycle"},
      {RuleId::Com001,
       FaultKind::Bus,
       AxisNeed::Any,
       {},
       "the axis's slave does not process one cycle's LRW (WKC 3 short)"},
      {RuleId::Com002, FaultKind::Bus, AxisNeed::None, {}, "the master sends nothing for 2 cycles"},
      {RuleId::Com003,
       FaultKind::Bus,
       AxisNeed::Any,
       {RuleId::Com004},
       "3 cycles are lost before the slaves; the axis's drive raises no ECatTErr"},
      {RuleId::Com004,
       FaultKind::Bus,
       AxisNeed::None,
       {},
       "one cycle's frame is lost after the slaves"},
      {RuleId::Com005,
       FaultKind::Bus,
       AxisNeed::None,
       {RuleId::Com004},
       "4 cycles are lost before the slaves (the drives raise ECatTErr)"},
      {RuleId::Esm001,
       FaultKind::Startup,
       AxisNeed::Any,
       {RuleId::Esm003},
       "the master requests OP from PRE-OP of the axis's slave (refused with 0x0011)"},
      {RuleId::Esm002,
       FaultKind::Startup,
       AxisNeed::Any,
       {},
       "the NC sends SE 0x1 to the axis while its slave is in SAFE-OP"},
      {RuleId::Esm003,
       FaultKind::Startup,
       AxisNeed::Any,
       {},
       "the axis's slave refuses SAFE-OP -> OP once (0x001D)"},
      {RuleId::Esm004,
       FaultKind::Startup,
       AxisNeed::Any,
       {},
       "the axis's slave powers up with an AL error (0x0050) that the master acknowledges"},
  };
  return table;
}

const FaultRecipe& recipe(RuleId rule) {
  for (const FaultRecipe& r : recipes()) {
    if (r.rule == rule) return r;
  }
  return recipes().front();  // unreachable: every rule has a row (checked by tests)
}

bool isIncrementalAxis(int axis) {
  return axis % 2 == 1;
}  // this simulator's set-up

// The faults scenario: every rule, spread over four axes and time (seconds), the bus faults
// last and apart, so that no two of them meet.
struct ScheduledFault {
  RuleId rule;
  double at_s;  // < 0: in the start-up
  int axis;
};
const std::vector<ScheduledFault>& faultsScenario() {
  static const std::vector<ScheduledFault> table = {
      {RuleId::Esm001, -1, 0},   {RuleId::Esm002, -1, 1},    {RuleId::Esm003, -1, 2},
      {RuleId::Esm004, -1, 3},   {RuleId::Se001, 0.60, 0},   {RuleId::Zp001, 0.60, 1},
      {RuleId::Se003, 0.60, 2},  {RuleId::Se004, 0.60, 3},   {RuleId::Zp003, 1.05, 0},
      {RuleId::Se002, 1.05, 1},  {RuleId::Ec001, 1.05, 2},   {RuleId::Zp002, 1.05, 3},
      {RuleId::Flt001, 1.50, 0}, {RuleId::Ec002, 1.50, 1},   {RuleId::Ec003, 1.50, 2},
      {RuleId::Ec004, 1.50, 3},  {RuleId::Msg001, 2.00, 0},  {RuleId::Sew001, 2.00, 1},
      {RuleId::Scw001, 2.00, 2}, {RuleId::Ssw001, 2.00, 3},  {RuleId::Sew003, 2.45, 0},
      {RuleId::Pt001, 2.45, 1},  {RuleId::Rdy001, 2.45, 2},  {RuleId::Sew002, 2.45, 3},
      {RuleId::Com001, 2.90, 0}, {RuleId::Com004, 3.05, -1}, {RuleId::Com002, 3.20, -1},
      {RuleId::Com003, 3.40, 2}, {RuleId::Com005, 3.80, -1},
  };
  return table;
}

}  // namespace

std::optional<Scenario> scenarioFromName(std::string_view name) {
  if (name == "commissioning") return Scenario::Commissioning;
  if (name == "faults") return Scenario::Faults;
  if (name == "soak") return Scenario::Soak;
  return std::nullopt;
}
const char* scenarioName(Scenario scenario) {
  switch (scenario) {
    case Scenario::Commissioning:
      return "commissioning";
    case Scenario::Faults:
      return "faults";
    case Scenario::Soak:
      return "soak";
  }
  return "?";
}
double defaultDuration(Scenario scenario) {
  switch (scenario) {
    case Scenario::Commissioning:
      return 3.0;
    case Scenario::Faults:
      return 4.3;
    case Scenario::Soak:
      return 60.0;
  }
  return 3.0;
}

std::vector<RuleId> companionsOf(RuleId rule) {
  return recipe(rule).companions;
}
const char* faultDescription(RuleId rule) {
  return recipe(rule).description;
}

std::optional<FaultRequest> parseFault(std::string_view text, std::string& error) {
  FaultRequest fault;
  fault.text = std::string(text);
  std::string_view rest = text;
  std::string_view axis_text;
  std::string_view time_text;
  if (auto colon = rest.find(':'); colon != std::string_view::npos) {
    axis_text = rest.substr(colon + 1);
    rest = rest.substr(0, colon);
  }
  if (auto at = rest.find('@'); at != std::string_view::npos) {
    time_text = rest.substr(at + 1);
    rest = rest.substr(0, at);
  }
  std::string code(rest);
  for (char& c : code) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  const RuleDef* rule = ruleByCode(code);
  if (rule == nullptr) {
    error = fmt::format("--fault {}: no rule '{}' (see `ncservo rules`)", text, code);
    return std::nullopt;
  }
  fault.rule = rule->id;
  const bool has_time = text.find('@') != std::string_view::npos;
  const bool has_axis = text.find(':') != std::string_view::npos;
  try {
    std::size_t used = 0;
    if ((has_time && time_text.empty()) || (has_axis && axis_text.empty())) {
      throw std::invalid_argument("empty");
    }
    if (!time_text.empty()) {
      fault.at_s = std::stod(std::string(time_text), &used);
      if (used != time_text.size() || !(*fault.at_s >= 0)) throw std::invalid_argument("time");
    }
    if (!axis_text.empty()) {
      fault.axis = std::stoi(std::string(axis_text), &used);
      if (used != axis_text.size() || *fault.axis < 0) throw std::invalid_argument("axis");
    }
  } catch (const std::exception&) {
    error = fmt::format("--fault {}: expected RULE[@SECONDS][:AXIS], e.g. SE-001@1.2:0", text);
    return std::nullopt;
  }
  return fault;
}

std::string resolveOptions(SimOptions& o) {
  if (o.axes < 1 || o.axes > 32) return fmt::format("--axes {}: from 1 to 32", o.axes);
  if (o.io_slaves < 0 || o.io_slaves > 32) {
    return fmt::format("--io-slaves {}: from 0 to 32", o.io_slaves);
  }
  if (o.cycle_us < 125 || o.cycle_us > 10000) {
    return fmt::format("--cycle-us {}: from 125 to 10000", o.cycle_us);
  }
  if (o.ready_mode != 0 && o.ready_mode != 1) {
    return fmt::format("--ready-mode {}: 0 or 1", o.ready_mode);
  }
  // A fifth of a cycle either way keeps every interval under 1.5 cycles (COM-002).
  if (o.jitter_us < 0 || o.jitter_us > o.cycle_us / 5) {
    return fmt::format("--jitter-us {}: from 0 to a fifth of the cycle ({})", o.jitter_us,
                       o.cycle_us / 5);
  }
  if (!(o.loss >= 0 && o.loss <= 0.5)) return fmt::format("--loss {}: from 0 to 0.5", o.loss);
  if (!o.duration_s) o.duration_s = defaultDuration(o.scenario);
  const double duration = *o.duration_s;
  const double start = o.startup ? kStartupSeconds : 0.0;
  if (!(duration >= 1.0 && duration <= 24 * 3600.0)) {
    return fmt::format("--duration {}: from 1 s to 24 h", duration);
  }
  if (o.scenario == Scenario::Faults) {
    if (o.axes < 4) return "--scenario faults needs at least 4 axes";
    if (!o.startup) return "--scenario faults needs the start-up (its ESM faults happen there)";
    if (duration < defaultDuration(Scenario::Faults)) {
      return fmt::format("--scenario faults needs --duration {} or more",
                         defaultDuration(Scenario::Faults));
    }
  }
  for (FaultRequest& f : o.faults) {
    const FaultRecipe& r = recipe(f.rule);
    const char* code = ruleDef(f.rule).code;
    if (r.kind == FaultKind::Startup) {
      if (!o.startup) return fmt::format("--fault {}: {} happens in the start-up", f.text, code);
      if (f.at_s) {
        return fmt::format("--fault {}: {} happens in the start-up; give no @time", f.text, code);
      }
    } else {
      // After the start-up and the enables; in a commissioning run before the emergency stop
      // and the disables that end it (at 53 % and 85 % of the run), else before the end.
      const double earliest = start + 0.45;
      const double latest =
          o.scenario == Scenario::Commissioning ? 0.53 * duration - 0.25 : duration - 0.4;
      if (latest < earliest) {
        return fmt::format("--fault {}: the run is too short for a fault; use --duration {:g}",
                           f.text, o.scenario == Scenario::Commissioning ? 2.5 : 1.5);
      }
      if (!f.at_s) f.at_s = std::clamp(0.43 * duration, earliest, latest);
      if (*f.at_s < earliest || *f.at_s > latest) {
        return fmt::format(
            "--fault {}: {} s is outside the quiet part of the run ({:g} s to {:g} s)", f.text,
            *f.at_s, earliest, latest);
      }
    }
    if (r.need == AxisNeed::None) {
      if (f.axis)
        return fmt::format("--fault {}: {} concerns the whole bus; no :axis", f.text, code);
      continue;
    }
    if (!f.axis) {
      int axis = 2 % o.axes;
      if (r.need == AxisNeed::Incremental && !isIncrementalAxis(axis)) axis = o.axes > 1 ? 1 : -1;
      if (r.need == AxisNeed::Absolute && isIncrementalAxis(axis)) axis = 0;
      if (axis < 0) {
        return fmt::format("--fault {}: {} needs an incremental axis (odd index): use --axes 2",
                           f.text, code);
      }
      f.axis = axis;
    }
    if (*f.axis >= o.axes) {
      return fmt::format("--fault {}: axis {} does not exist (--axes {})", f.text, *f.axis, o.axes);
    }
    if (r.need == AxisNeed::Incremental && !isIncrementalAxis(*f.axis)) {
      return fmt::format("--fault {}: {} needs an incremental axis (odd index)", f.text, code);
    }
    if (r.need == AxisNeed::Absolute && isIncrementalAxis(*f.axis)) {
      return fmt::format("--fault {}: {} needs an absolute axis (even index)", f.text, code);
    }
  }
  return {};
}

// --- the segment ---

namespace {

enum class SlaveKind : std::uint8_t { Servo, OutputTerminal, InputTerminal };

// An EtherCAT slave controller: register memory, FMMUs and the AL state machine, driven only
// by what the master writes.
struct Esc {
  SlaveKind kind = SlaveKind::Servo;
  int axis = -1;     // for a servo
  int position = 0;  // ring position
  std::vector<std::uint8_t> mem = std::vector<std::uint8_t>(kEscMemory, 0);
  std::uint8_t state = kInit;
  bool error = false;
  std::uint16_t code = 0;
  std::uint8_t pending = 0;  // a transition under way
  int pending_frames = 0;
  int transition_frames = 1;
  bool refuse_next_op = false;  // ESM-003
  bool outputs_taken = false;   // this cycle's LRW wrote its outputs
  bool skip_next_lrw = false;   // COM-001

  std::uint16_t station() const { return static_cast<std::uint16_t>(getLe(&mem[kRegStation], 2)); }
  void publishAlStatus() {
    putLe(&mem[kRegAlStatus], static_cast<std::uint16_t>(state | (error ? kAlErrorBit : 0)), 2);
    putLe(&mem[kRegAlStatusCode], code, 2);
  }
  void onAlControl(std::uint16_t value) {
    const auto requested = static_cast<std::uint8_t>(value & 0x0F);
    if (error) {
      if ((value & kAlErrorBit) == 0) return;  // an error must be acknowledged first
      error = false;
      code = 0;
    }
    pending = 0;
    if (requested == state) {
      publishAlStatus();
      return;
    }
    const bool allowed = alTransitionAllowed(state, requested);  // PROTOCOL.md §8
    if (!allowed || (requested == kOp && refuse_next_op)) {
      if (requested == kOp && refuse_next_op && allowed) {
        refuse_next_op = false;
        code = kCodeInvalidOutputs;
      } else {
        code = kCodeInvalidTransition;
      }
      error = true;
    } else {
      pending = requested;
      pending_frames = transition_frames;
    }
    publishAlStatus();
  }
  // Once per frame passing through.
  void tick() {
    if (pending != 0 && --pending_frames <= 0) {
      state = pending;
      pending = 0;
      publishAlStatus();
    }
  }
  bool processData() const { return state == kSafeOp || state == kOp; }
};

struct Datagram {
  std::uint8_t command = 0;
  std::uint8_t index = 0;
  std::uint16_t adp = 0;
  std::uint16_t ado = 0;  // with adp, the logical address of LRD/LWR/LRW
  std::vector<std::uint8_t> data;
  std::uint16_t wkc = 0;
  std::uint32_t logical() const {
    return static_cast<std::uint32_t>(adp) | (static_cast<std::uint32_t>(ado) << 16);
  }
};

struct FrameGroup {  // the slaves whose process data one cyclic frame carries
  std::vector<int> slaves;
  std::uint32_t base = 0;
  std::size_t size = 0;
};

// The master's walk of every slave to one AL state, with acknowledgement of refusals.
struct AlWalk {
  std::uint8_t target = kInit;
  std::vector<bool> need_request, need_ack, done;
  std::vector<std::uint8_t> ack_value;
  std::vector<std::uint8_t> first_request;  // ESM-001: what the first request asks for
  bool active = false;

  void start(std::uint8_t state, std::size_t slaves, bool request) {
    target = state;
    need_request.assign(slaves, request);
    need_ack.assign(slaves, false);
    done.assign(slaves, false);
    ack_value.assign(slaves, 0);
    first_request.assign(slaves, 0);
    active = true;
  }
  bool finished() const {
    return std::all_of(done.begin(), done.end(), [](bool d) { return d; });
  }
};

}  // namespace

struct Simulator::Impl {
  SimOptions o;
  std::int64_t cycle_ns;
  std::int64_t duration_ns;
  std::int64_t plan_start_ns;  // since the capture's start
  std::int64_t return_delay_ns;
  Rng rng;
  std::vector<Esc> escs;
  std::vector<int> servo_slave;  // axis -> ring position
  std::vector<FrameGroup> groups;
  std::vector<SimAxisLayout> axis_layout;
  std::vector<DriveModel> drives;
  std::vector<NcAxis> ncs;
  std::vector<std::optional<TxPdo>> latest_inputs;  // per axis, from this cycle's returned frame
  std::vector<std::vector<std::uint8_t>> images;    // per group: the master's process image
  std::uint8_t datagram_index = 0;
  std::vector<std::uint8_t> bytes;
  // faults in time
  struct TimedFault {
    RuleId rule;
    std::int64_t at_ns;
    int axis;
    bool done = false;
  };
  std::vector<TimedFault> bus_faults;
  struct DriveFaultEvent {
    std::int64_t at_ns;
    int axis;
    std::uint32_t cause;
    bool done = false;
  };
  std::vector<DriveFaultEvent> drive_faults;
  int skip_slots = 0;              // COM-002
  int lose_before_slaves = 0;      // COM-003, COM-005
  bool lose_after_slaves = false;  // COM-004
  int esm001_slave = -1;
  std::int64_t soak_planned_until_ns = 0;
  std::uint64_t frames = 0;

  explicit Impl(const SimOptions& options)
      : o(options),
        cycle_ns(static_cast<std::int64_t>(options.cycle_us) * kUs),
        duration_ns(static_cast<std::int64_t>(std::llround(*options.duration_s * 1e9))),
        plan_start_ns(options.startup ? static_cast<std::int64_t>(kStartupSeconds * 1e9) : 0),
        rng(options.seed) {
    buildSegment();
    // the ring's round trip: a few microseconds plus a quarter per slave
    return_delay_ns = (2 + static_cast<std::int64_t>(escs.size()) / 4) * kUs;
    for (int a = 0; a < o.axes; ++a) {
      DriveSetup setup;
      setup.axis = a;
      setup.incremental = isIncrementalAxis(a);
      setup.ready_mode = o.ready_mode;
      setup.seed = o.seed;
      drives.emplace_back(setup);
      ncs.emplace_back(setup.incremental);
    }
    latest_inputs.assign(static_cast<std::size_t>(o.axes), std::nullopt);
    planScenario();
    for (const FaultRequest& f : o.faults)
      applyFault(f.rule, f.at_s.value_or(-1), f.axis.value_or(-1));
    if (o.scenario == Scenario::Faults) {
      for (const ScheduledFault& f : faultsScenario()) applyFault(f.rule, f.at_s, f.axis);
    }
  }

  // Ring order: servo 0, terminal 0, servo 1, terminal 1, ..., then the rest.
  void buildSegment() {
    const int total = o.axes + o.io_slaves;
    int servo = 0, terminal = 0;
    for (int pos = 0; pos < total; ++pos) {
      Esc esc;
      const bool take_servo = servo < o.axes && (terminal >= o.io_slaves || servo <= terminal);
      if (take_servo) {
        esc.kind = SlaveKind::Servo;
        esc.axis = servo++;
        servo_slave.push_back(pos);
      } else {
        esc.kind = terminal % 2 == 0 ? SlaveKind::OutputTerminal : SlaveKind::InputTerminal;
        ++terminal;
      }
      esc.position = pos;
      esc.mem[kRegType] = 0x11;
      esc.transition_frames = static_cast<int>(rng.between(1, 3));
      esc.publishAlStatus();
      escs.push_back(std::move(esc));
    }
    // Frames: at most 29 servos and 1450 bytes of process data each.
    FrameGroup group;
    int servos_in_group = 0;
    for (int pos = 0; pos < total; ++pos) {
      const std::size_t need = outLen(escs[pos]) + inLen(escs[pos]);
      const bool servo_slave_here = escs[pos].kind == SlaveKind::Servo;
      if (!group.slaves.empty() && (group.size + need > kMaxLrwData ||
                                    (servo_slave_here && servos_in_group == kMaxServosPerFrame))) {
        groups.push_back(std::move(group));
        group = FrameGroup{};
        servos_in_group = 0;
      }
      group.slaves.push_back(pos);
      group.size += need;
      if (servo_slave_here) ++servos_in_group;
    }
    groups.push_back(std::move(group));
    for (std::size_t g = 0; g < groups.size(); ++g) {
      FrameGroup& fg = groups[g];
      fg.base = kLogicalBase + static_cast<std::uint32_t>(g) * kLogicalFrameStride;
      images.emplace_back(fg.size, 0);
      // Logical addresses of each slave's outputs and inputs.
      std::uint32_t cursor = fg.base;
      if (o.layout == LayoutKind::Default) {
        for (int pos : fg.slaves) {
          escOut(pos) = cursor;
          cursor += static_cast<std::uint32_t>(outLen(escs[pos]));
        }
        for (int pos : fg.slaves) {
          escIn(pos) = cursor;
          cursor += static_cast<std::uint32_t>(inLen(escs[pos]));
        }
      } else {
        for (int pos : fg.slaves) {
          escOut(pos) = cursor;
          cursor += static_cast<std::uint32_t>(outLen(escs[pos]));
          escIn(pos) = cursor;
          cursor += static_cast<std::uint32_t>(inLen(escs[pos]));
        }
      }
    }
    for (int a = 0; a < o.axes; ++a) {
      const int pos = servo_slave[static_cast<std::size_t>(a)];
      axis_layout.push_back({a, fmt::format("axis{}", a),
                             static_cast<std::uint16_t>(kFirstStation + pos), escOut(pos),
                             escIn(pos)});
    }
  }
  std::vector<std::uint32_t> out_addr, in_addr;
  std::uint32_t& escOut(int pos) {
    if (out_addr.size() < escs.size()) out_addr.resize(escs.size());
    return out_addr[static_cast<std::size_t>(pos)];
  }
  std::uint32_t& escIn(int pos) {
    if (in_addr.size() < escs.size()) in_addr.resize(escs.size());
    return in_addr[static_cast<std::size_t>(pos)];
  }
  static std::size_t outLen(const Esc& e) {
    return e.kind == SlaveKind::Servo ? kRxPdoSize : e.kind == SlaveKind::OutputTerminal ? 1 : 0;
  }
  static std::size_t inLen(const Esc& e) {
    return e.kind == SlaveKind::Servo ? kTxPdoSize : e.kind == SlaveKind::InputTerminal ? 1 : 0;
  }
  std::uint16_t outPhys(const Esc& e) const {
    return e.kind == SlaveKind::Servo ? kServoRxPhys : kOutTerminalPhys;
  }
  std::uint16_t inPhys(const Esc& e) const {
    return e.kind == SlaveKind::Servo ? kServoTxPhys : kInTerminalPhys;
  }

  // --- scenarios ---

  std::int64_t at(double seconds) const {
    return static_cast<std::int64_t>(std::llround(seconds * 1e9));
  }

  void planScenario() {
    const double base = static_cast<double>(plan_start_ns) * 1e-9;
    const double d = *o.duration_s;
    if (o.scenario == Scenario::Soak) return;  // planned period by period (planSoak)
    for (int a = 0; a < o.axes; ++a) {
      NcAxis& nc = ncs[static_cast<std::size_t>(a)];
      const double rpm = (a % 2 ? -1.0 : 1.0) * (600 + 300 * (a % 4));
      nc.schedule({at(base + 0.05 + 0.01 * (a % 8)), NcAction::Enable});
      nc.schedule({at(base + 0.15), NcAction::Speed, rpm});
      if (o.scenario == Scenario::Faults) continue;
      if (isIncrementalAxis(a)) nc.schedule({at(base + 0.30), NcAction::ZeroPulse});
      nc.schedule({at(base + 0.55), NcAction::Table, static_cast<double>(a % 3 + 2)});
      nc.schedule({at(0.53 * d), NcAction::Emergency, 150});
      nc.schedule({at(0.62 * d), NcAction::Table, 1});
      nc.schedule({at(0.78 * d), NcAction::Speed, 0});
      nc.schedule({at(0.85 * d), NcAction::Disable});
    }
    if (o.scenario == Scenario::Commissioning) {
      drive_faults.push_back({at(base + 0.8), 1 % o.axes, bits::kFollowing});
    }
  }

  // Soak: a 10 s pattern repeated, planned a period ahead (constant memory).
  void planSoak(std::int64_t now_ns) {
    constexpr std::int64_t kPeriod = 10 * kSecond;
    while (soak_planned_until_ns <= now_ns + kPeriod) {
      const std::int64_t p = soak_planned_until_ns == 0 ? plan_start_ns : soak_planned_until_ns;
      const std::int64_t k = (p - plan_start_ns) / kPeriod;
      for (int a = 0; a < o.axes; ++a) {
        NcAxis& nc = ncs[static_cast<std::size_t>(a)];
        const auto ka = k + a;
        if (k == 0) nc.schedule({p + 50 * kMs + 10 * kMs * (a % 8), NcAction::Enable});
        nc.schedule({p + 500 * kMs, NcAction::Speed,
                     (ka % 2 ? -1.0 : 1.0) * static_cast<double>(500 + 150 * (ka % 5))});
        if (isIncrementalAxis(a)) nc.schedule({p + 2 * kSecond, NcAction::ZeroPulse});
        nc.schedule({p + 4 * kSecond, NcAction::Table, static_cast<double>(ka % 4 + 1)});
        if (k % 3 == 2) nc.schedule({p + 6 * kSecond, NcAction::Emergency, 100});
        nc.schedule({p + 9 * kSecond, NcAction::Speed, 0});
      }
      if (k % 6 == 5) {
        drive_faults.push_back({p + 7500 * kMs, static_cast<int>(k / 6 % o.axes), bits::kOverload});
      }
      soak_planned_until_ns = p + kPeriod;
    }
    // drop the faults already raised (constant memory)
    drive_faults.erase(std::remove_if(drive_faults.begin(), drive_faults.end(),
                                      [](const DriveFaultEvent& e) { return e.done; }),
                       drive_faults.end());
  }

  void applyFault(RuleId rule, double at_s, int axis) {
    const std::int64_t t = at(at_s);
    const auto a = static_cast<std::size_t>(std::max(axis, 0));
    auto nc = [&](std::int64_t when, NcAction action, double value = 0) {
      ncs[a].schedule({when, action, value});
    };
    auto quirk = [&](DriveQuirk q) { drives[a].arm(q, t); };
    auto driveFault = [&] { drive_faults.push_back({t, axis, bits::kFollowing}); };
    switch (rule) {
      case RuleId::Se001:
        nc(t - 150 * kMs, NcAction::Disable);
        nc(t, NcAction::IllegalEnable);
        break;
      case RuleId::Se002:
        nc(t - 100 * kMs, NcAction::Disable);
        quirk(DriveQuirk::SpuriousEnable);
        nc(t + 100 * kMs, NcAction::Enable);
        break;
      case RuleId::Se003:
        nc(t, NcAction::Disable);
        quirk(DriveQuirk::LateDisable);
        nc(t + 250 * kMs, NcAction::Enable);
        break;
      case RuleId::Se004:
        nc(t - 100 * kMs, NcAction::Disable);
        quirk(DriveQuirk::IgnoreEnable);
        nc(t, NcAction::Enable);
        break;
      case RuleId::Zp001:
        nc(t, NcAction::ZeroPulse);
        quirk(DriveQuirk::HoldZPulseAck);
        break;
      case RuleId::Zp002:
        quirk(DriveQuirk::SpuriousZPulseAck);
        break;
      case RuleId::Zp003:
        nc(t, NcAction::ZeroPulseAbsolute, 30);
        break;
      case RuleId::Ec001:
        quirk(DriveQuirk::SpuriousClearAck);
        break;
      case RuleId::Ec002:
        driveFault();
        nc(t, NcAction::HoldErrorClear, 100);
        break;
      case RuleId::Ec003:
        driveFault();
        quirk(DriveQuirk::HoldClearAck);
        break;
      case RuleId::Ec004:
        driveFault();
        quirk(DriveQuirk::IgnoreClear);
        break;
      case RuleId::Sew001:
        quirk(DriveQuirk::CauseWithoutSummary);
        break;
      case RuleId::Sew002:
        quirk(DriveQuirk::SummaryWithoutCause);
        break;
      case RuleId::Sew003:
        quirk(DriveQuirk::ReservedErrorBit);
        break;
      case RuleId::Ssw001:
        quirk(DriveQuirk::ReservedStatusBit);
        break;
      case RuleId::Scw001:
        nc(t, NcAction::ReservedBit, 5);
        break;
      case RuleId::Rdy001:
        quirk(DriveQuirk::ReadyInverted);
        break;
      case RuleId::Flt001:
        driveFault();
        quirk(DriveQuirk::SlowFaultReaction);
        break;
      case RuleId::Pt001:
        nc(t, NcAction::Table, 8);
        quirk(DriveQuirk::IgnoreTable);
        break;
      case RuleId::Msg001:
        quirk(DriveQuirk::UndefinedMessage);
        break;
      case RuleId::Com003:
        quirk(DriveQuirk::SilentTimeout);
        [[fallthrough]];
      case RuleId::Com001:
      case RuleId::Com002:
      case RuleId::Com004:
      case RuleId::Com005:
        bus_faults.push_back({rule, t, axis});
        break;
      case RuleId::Esm001:
        esm001_slave = servo_slave[a];
        break;
      case RuleId::Esm002:
        ncs[a].setEnableBeforeOp(true);
        break;
      case RuleId::Esm003:
        escs[static_cast<std::size_t>(servo_slave[a])].refuse_next_op = true;
        break;
      case RuleId::Esm004: {
        Esc& esc = escs[static_cast<std::size_t>(servo_slave[a])];
        esc.error = true;
        esc.code = kCodePowerUp;
        esc.publishAlStatus();
        break;
      }
    }
  }

  // --- the ring ---

  void readRegisters(Esc& esc, Datagram& dg) {
    for (std::size_t i = 0; i < dg.data.size(); ++i) {
      const std::size_t reg = dg.ado + i;
      dg.data[i] = reg < kEscMemory ? esc.mem[reg] : 0;
    }
  }
  void writeRegisters(Esc& esc, const Datagram& dg) {
    for (std::size_t i = 0; i < dg.data.size(); ++i) {
      const std::size_t reg = dg.ado + i;
      if (reg >= kEscMemory || (reg >= kRegAlStatus && reg < kRegAlStatus + 6)) continue;
      esc.mem[reg] = dg.data[i];
    }
    if (dg.ado <= kRegAlControl && dg.ado + dg.data.size() >= kRegAlControl + 2u) {
      esc.onAlControl(static_cast<std::uint16_t>(getLe(&esc.mem[kRegAlControl], 2)));
    }
  }
  // An LRD/LWR/LRW through the slave's FMMUs; the working-counter increment.
  std::uint16_t logicalAccess(Esc& esc, Datagram& dg) {
    if (!esc.processData() || (esc.skip_next_lrw && dg.command == ecat::kLrw)) return 0;
    bool read = false, wrote = false;
    const std::uint64_t start = dg.logical();
    const std::uint64_t end = start + dg.data.size();
    for (std::size_t f = 0; f < 3; ++f) {
      const std::uint8_t* fmmu = &esc.mem[kRegFmmu + kFmmuSize * f];
      if ((fmmu[12] & 1) == 0) continue;
      const std::uint64_t lstart = getLe(fmmu, 4);
      const std::uint64_t lend = lstart + getLe(fmmu + 4, 2);
      const std::uint64_t from = std::max(start, lstart), to = std::min(end, lend);
      if (from >= to) continue;
      const std::size_t phys = getLe(fmmu + 8, 2) + (from - lstart);
      const std::size_t offset = from - start;
      const std::size_t count = to - from;
      if (phys + count > kEscMemory) continue;
      if (fmmu[11] == 1 && ecat::readsSlaves(dg.command)) {
        std::memcpy(&dg.data[offset], &esc.mem[phys], count);
        read = true;
      } else if (fmmu[11] == 2 && ecat::writesSlaves(dg.command)) {
        std::memcpy(&esc.mem[phys], &dg.data[offset], count);
        wrote = true;
        esc.outputs_taken = true;
      }
    }
    if (dg.command == ecat::kLrw)
      return static_cast<std::uint16_t>((read ? 1 : 0) + (wrote ? 2 : 0));
    return static_cast<std::uint16_t>(read || wrote ? 1 : 0);
  }
  void passRing(std::vector<Datagram>& frame, std::int64_t now_ns) {
    for (Esc& esc : escs) {
      putLe(&esc.mem[kRegSystemTime], static_cast<std::uint64_t>(now_ns - kEpochNs), 8);
      for (Datagram& dg : frame) {
        switch (dg.command) {
          case ecat::kAprd:
          case ecat::kApwr:
            if (dg.adp == 0) {
              if (dg.command == ecat::kAprd)
                readRegisters(esc, dg);
              else
                writeRegisters(esc, dg);
              ++dg.wkc;
            }
            ++dg.adp;
            break;
          case ecat::kFprd:
          case ecat::kFpwr:
            if (dg.adp == esc.station()) {
              if (dg.command == ecat::kFprd)
                readRegisters(esc, dg);
              else
                writeRegisters(esc, dg);
              ++dg.wkc;
            }
            break;
          case ecat::kBrd: {
            for (std::size_t i = 0; i < dg.data.size(); ++i) {
              const std::size_t reg = dg.ado + i;
              dg.data[i] |= reg < kEscMemory ? esc.mem[reg] : 0;
            }
            ++dg.wkc;
            ++dg.adp;
            break;
          }
          case ecat::kBwr:
            writeRegisters(esc, dg);
            ++dg.wkc;
            ++dg.adp;
            break;
          case ecat::kFrmw:
            if (dg.adp == esc.station())
              readRegisters(esc, dg);
            else
              writeRegisters(esc, dg);
            ++dg.wkc;
            break;
          case ecat::kLrd:
          case ecat::kLwr:
          case ecat::kLrw:
            dg.wkc = static_cast<std::uint16_t>(dg.wkc + logicalAccess(esc, dg));
            break;
          default:
            break;
        }
      }
      esc.skip_next_lrw = false;
      esc.tick();
    }
  }

  // --- frames on the wire ---

  Datagram registerDatagram(std::uint8_t command, std::uint16_t adp, std::uint16_t ado,
                            std::size_t length) {
    Datagram dg;
    dg.command = command;
    dg.index = datagram_index++;
    dg.adp = adp;
    dg.ado = ado;
    dg.data.assign(length, 0);
    return dg;
  }
  void serialize(const std::vector<Datagram>& frame, bool returned) {
    bytes.assign(kBroadcastMac.begin(), kBroadcastMac.end());
    std::array<std::uint8_t, 6> source = kMasterMac;
    if (returned) source[0] |= kLocallyAdministered;
    bytes.insert(bytes.end(), source.begin(), source.end());
    bytes.push_back(static_cast<std::uint8_t>(ecat::kEtherType >> 8));
    bytes.push_back(static_cast<std::uint8_t>(ecat::kEtherType & 0xFF));
    std::size_t length = 0;
    for (const Datagram& dg : frame)
      length += ecat::kDatagramHeaderSize + dg.data.size() + ecat::kWkcSize;
    const auto header = static_cast<std::uint16_t>((length & ecat::kLengthMask) |
                                                   (ecat::kFrameTypeDatagrams << 12));
    bytes.push_back(static_cast<std::uint8_t>(header));
    bytes.push_back(static_cast<std::uint8_t>(header >> 8));
    for (std::size_t i = 0; i < frame.size(); ++i) {
      const Datagram& dg = frame[i];
      std::uint8_t h[ecat::kDatagramHeaderSize] = {};
      h[0] = dg.command;
      h[1] = dg.index;
      putLe(h + 2, dg.adp, 2);
      putLe(h + 4, dg.ado, 2);
      putLe(h + 6, dg.data.size() | (i + 1 < frame.size() ? ecat::kMoreBit : 0), 2);
      bytes.insert(bytes.end(), h, h + sizeof h);
      bytes.insert(bytes.end(), dg.data.begin(), dg.data.end());
      bytes.push_back(static_cast<std::uint8_t>(dg.wkc));
      bytes.push_back(static_cast<std::uint8_t>(dg.wkc >> 8));
    }
    if (bytes.size() < kMinFrame) bytes.resize(kMinFrame, 0);
  }
  bool emit(const FrameSink& sink, std::int64_t t_ns) {
    ++frames;
    return sink(SimFrame{kEpochNs + t_ns, bytes.data(), bytes.size()});
  }
  // Sends a frame round the ring and captures both copies. `lost_before`: nothing returns and
  // no slave saw it; `lost_after`: the slaves processed it but the returned copy is lost.
  // `came_back` (when given) says whether the returned copy reached the master.
  bool exchange(const FrameSink& sink, std::vector<Datagram>& frame, std::int64_t t_ns,
                bool lost_before = false, bool lost_after = false, bool* came_back = nullptr) {
    if (came_back != nullptr) *came_back = false;
    serialize(frame, false);
    if (!emit(sink, t_ns)) return false;
    if (lost_before) return true;
    passRing(frame, kEpochNs + t_ns);
    if (lost_after) return true;
    if (came_back != nullptr) *came_back = true;
    serialize(frame, true);
    return emit(sink, t_ns + return_delay_ns);
  }

  // --- the master's start-up ---

  bool alFrame(const FrameSink& sink, AlWalk& walk, std::int64_t t_ns) {
    std::vector<Datagram> frame;
    const std::size_t n = escs.size();
    const bool acks =
        std::find(walk.need_ack.begin(), walk.need_ack.end(), true) != walk.need_ack.end();
    const bool requests = std::find(walk.need_request.begin(), walk.need_request.end(), true) !=
                          walk.need_request.end();
    for (std::size_t s = 0; s < n; ++s) {
      const auto station = static_cast<std::uint16_t>(kFirstStation + s);
      if (acks) {
        if (!walk.need_ack[s]) continue;
        Datagram dg = registerDatagram(ecat::kFpwr, station, kRegAlControl, 2);
        putLe(dg.data.data(), walk.ack_value[s], 2);
        frame.push_back(std::move(dg));
        walk.need_ack[s] = false;
        walk.need_request[s] = true;
      } else if (requests) {
        if (!walk.need_request[s]) continue;
        Datagram dg = registerDatagram(ecat::kFpwr, station, kRegAlControl, 2);
        const std::uint8_t value = walk.first_request[s] != 0 ? walk.first_request[s] : walk.target;
        walk.first_request[s] = 0;
        putLe(dg.data.data(), value, 2);
        frame.push_back(std::move(dg));
        walk.need_request[s] = false;
      } else if (!walk.done[s]) {
        frame.push_back(registerDatagram(ecat::kFprd, station, kRegAlStatus, 6));
      }
    }
    const bool poll = !acks && !requests;
    if (!exchange(sink, frame, t_ns)) return false;
    if (poll) {
      for (const Datagram& dg : frame) {
        if (dg.wkc == 0) continue;
        const std::size_t s = static_cast<std::size_t>(dg.adp - kFirstStation);
        const auto status = static_cast<std::uint8_t>(dg.data[0]);
        if (status & kAlErrorBit) {
          walk.need_ack[s] = true;
          walk.ack_value[s] = static_cast<std::uint8_t>((status & 0x0F) | kAlErrorBit);
        } else if ((status & 0x0F) == walk.target) {
          walk.done[s] = true;
        }
      }
      if (walk.finished()) walk.active = false;
    }
    return true;
  }

  bool configFrame(const FrameSink& sink, bool sync_managers, std::int64_t t_ns) {
    std::vector<Datagram> frame;
    for (std::size_t s = 0; s < escs.size(); ++s) {
      const Esc& esc = escs[s];
      const auto station = static_cast<std::uint16_t>(kFirstStation + s);
      const bool servo = esc.kind == SlaveKind::Servo;
      struct Entry {
        std::uint16_t phys;
        std::size_t length;
        std::uint32_t logical;
        bool outputs;
      };
      std::vector<Entry> entries;
      if (outLen(esc) > 0) entries.push_back({outPhys(esc), outLen(esc), out_addr[s], true});
      if (inLen(esc) > 0) entries.push_back({inPhys(esc), inLen(esc), in_addr[s], false});
      if (sync_managers) {
        // Servos: SM2 outputs, SM3 inputs; the digital terminals have one SM0 (as EL2008/EL1008).
        Datagram dg = registerDatagram(
            ecat::kFpwr, station, servo ? kRegSyncManager + 2 * kSyncManagerSize : kRegSyncManager,
            entries.size() * kSyncManagerSize);
        for (std::size_t e = 0; e < entries.size(); ++e) {
          std::uint8_t* sm = &dg.data[e * kSyncManagerSize];
          putLe(sm, entries[e].phys, 2);
          putLe(sm + 2, entries[e].length, 2);
          sm[4] = entries[e].outputs ? 0x64 : 0x20;  // buffered, write (watchdog) / read
          sm[6] = 0x01;                              // activate
        }
        frame.push_back(std::move(dg));
      } else {
        Datagram dg = registerDatagram(ecat::kFpwr, station, kRegFmmu, entries.size() * kFmmuSize);
        for (std::size_t e = 0; e < entries.size(); ++e) {
          std::uint8_t* fmmu = &dg.data[e * kFmmuSize];
          putLe(fmmu, entries[e].logical, 4);
          putLe(fmmu + 4, entries[e].length, 2);
          fmmu[6] = 0;  // start bit
          fmmu[7] = 7;  // stop bit
          putLe(fmmu + 8, entries[e].phys, 2);
          fmmu[10] = 0;
          fmmu[11] = entries[e].outputs ? 2 : 1;  // 2 write = outputs, 1 read = inputs
          fmmu[12] = 1;
        }
        frame.push_back(std::move(dg));
      }
    }
    return exchange(sink, frame, t_ns);
  }

  // --- the cycle ---

  bool cyclicFrames(const FrameSink& sink, std::int64_t t_ns, std::uint64_t cycle) {
    bool lost_before = lose_before_slaves > 0;
    bool lost_after = lose_after_slaves || (o.loss > 0 && rng.uniform() < o.loss);
    if (lose_before_slaves > 0) --lose_before_slaves;
    lose_after_slaves = false;
    for (Esc& esc : escs) esc.outputs_taken = false;
    std::fill(latest_inputs.begin(), latest_inputs.end(), std::nullopt);
    for (std::size_t g = 0; g < groups.size(); ++g) {
      FrameGroup& fg = groups[g];
      std::vector<std::uint8_t>& image = images[g];
      // the NC's outputs, and the terminals', into the master's image
      for (int pos : fg.slaves) {
        const Esc& esc = escs[static_cast<std::size_t>(pos)];
        const std::size_t at_out = out_addr[static_cast<std::size_t>(pos)] - fg.base;
        if (esc.kind == SlaveKind::Servo) {
          encodeRx(outputs_[static_cast<std::size_t>(esc.axis)], &image[at_out]);
        } else if (esc.kind == SlaveKind::OutputTerminal) {
          image[at_out] = static_cast<std::uint8_t>(1U << (cycle / 100 % 8));
        }
      }
      // The same datagrams every cycle, refilled in place: a long run allocates nothing.
      std::vector<Datagram>& frame = cyclic_frames[g];
      frame.resize(g == 0 ? 2 : 1);
      Datagram& lrw = frame[0];
      lrw.command = ecat::kLrw;
      lrw.index = datagram_index++;
      lrw.adp = static_cast<std::uint16_t>(fg.base & 0xFFFF);
      lrw.ado = static_cast<std::uint16_t>(fg.base >> 16);
      lrw.data.assign(image.begin(), image.end());
      lrw.wkc = 0;
      if (g == 0) {
        Datagram& dc = frame[1];
        dc.command = ecat::kFrmw;
        dc.index = datagram_index++;
        dc.adp = kFirstStation;
        dc.ado = kRegSystemTime;
        dc.data.assign(8, 0);
        dc.wkc = 0;
      }
      const std::int64_t at_ns = t_ns + static_cast<std::int64_t>(g) * 2 * return_delay_ns;
      bool came_back = false;
      if (!exchange(sink, frame, at_ns, lost_before, lost_after, &came_back)) return false;
      if (!came_back || frame[0].wkc == 0) continue;
      image.assign(frame[0].data.begin(), frame[0].data.end());  // the inputs the slaves wrote
      for (int pos : fg.slaves) {
        const Esc& esc = escs[static_cast<std::size_t>(pos)];
        if (esc.kind != SlaveKind::Servo) continue;
        const std::size_t at_in = in_addr[static_cast<std::size_t>(pos)] - fg.base;
        TxPdo in;
        const std::uint8_t* p = &image[at_in];
        in.actpos = static_cast<std::int64_t>(getLe(p, 8));
        in.ssw = static_cast<std::uint32_t>(getLe(p + 8, 4));
        in.sew = static_cast<std::uint32_t>(getLe(p + 12, 4));
        latest_inputs[static_cast<std::size_t>(esc.axis)] = in;
      }
    }
    return true;
  }
  std::vector<RxPdo> outputs_;
  std::vector<std::vector<Datagram>> cyclic_frames;  // per group, reused every cycle

  void stepDrives(std::int64_t now_ns) {
    for (DriveFaultEvent& e : drive_faults) {
      if (!e.done && now_ns >= e.at_ns) {
        drives[static_cast<std::size_t>(e.axis)].raiseFault(e.cause);
        e.done = true;
      }
    }
    for (int a = 0; a < o.axes; ++a) {
      Esc& esc = escs[static_cast<std::size_t>(servo_slave[static_cast<std::size_t>(a)])];
      if (!esc.processData()) continue;
      DriveModel& drive = drives[static_cast<std::size_t>(a)];
      drive.setOperational(esc.state == kOp);
      if (esc.outputs_taken) {
        const RxPdo rx = decodeRx(&esc.mem[kServoRxPhys]);
        drive.step(&rx, now_ns);
      } else {
        drive.step(nullptr, now_ns);
      }
      encodeTx(drive.inputs(), &esc.mem[kServoTxPhys]);
    }
    for (Esc& esc : escs) {
      if (esc.kind == SlaveKind::InputTerminal) {
        esc.mem[kInTerminalPhys] = static_cast<std::uint8_t>(now_ns / (50 * kMs));
      }
    }
  }

  void startBusFaults(std::int64_t now_ns) {
    for (TimedFault& f : bus_faults) {
      if (f.done || now_ns < f.at_ns) continue;
      f.done = true;
      switch (f.rule) {
        case RuleId::Com001:
          escs[static_cast<std::size_t>(servo_slave[static_cast<std::size_t>(f.axis)])]
              .skip_next_lrw = true;
          break;
        case RuleId::Com002:
          skip_slots = 2;
          break;
        case RuleId::Com003:
          lose_before_slaves = 3;
          break;
        case RuleId::Com004:
          lose_after_slaves = true;
          break;
        case RuleId::Com005:
          lose_before_slaves = 4;
          break;
        default:
          break;
      }
    }
  }

  std::optional<std::uint64_t> run(const FrameSink& sink) {
    outputs_.assign(static_cast<std::size_t>(o.axes), RxPdo{});
    cyclic_frames.assign(groups.size(), {});
    std::int64_t t = 0;
    const std::int64_t step_ns = std::min<std::int64_t>(cycle_ns, kMs);
    if (o.startup) {
      if (!startup(sink, t, step_ns)) return std::nullopt;
    } else {
      for (Esc& esc : escs) {  // a capture that begins with the segment already in OP
        esc.state = kOp;
        esc.publishAlStatus();
      }
      for (std::size_t s = 0; s < escs.size(); ++s) {
        putLe(&escs[s].mem[kRegStation], kFirstStation + s, 2);
        configureDirect(s);
      }
      stepDrives(0);
    }
    // Cyclic exchange: SAFE-OP first, then the master walks every slave to OP.
    AlWalk walk;
    const std::uint64_t safe_op_cycles =
        static_cast<std::uint64_t>(std::max<std::int64_t>(10, 20 * kMs / cycle_ns));
    const std::int64_t first_cycle = t;
    bool operational = !o.startup;
    for (NcAxis& nc : ncs) nc.setOperational(operational);
    for (std::uint64_t cycle = 0;; ++cycle) {
      const std::int64_t slot = first_cycle + static_cast<std::int64_t>(cycle) * cycle_ns;
      if (slot >= duration_ns) break;
      if (o.scenario == Scenario::Soak) planSoak(slot);
      startBusFaults(slot);
      std::int64_t send = slot;
      if (o.jitter_us > 0) send += rng.between(-o.jitter_us, o.jitter_us) * kUs;
      for (int a = 0; a < o.axes; ++a) {
        const auto& in = latest_inputs[static_cast<std::size_t>(a)];
        outputs_[static_cast<std::size_t>(a)] =
            ncs[static_cast<std::size_t>(a)].step(in ? &*in : nullptr, slot);
      }
      if (skip_slots > 0) {
        --skip_slots;
        for (Esc& esc : escs) esc.outputs_taken = false;
        std::fill(latest_inputs.begin(), latest_inputs.end(), std::nullopt);
      } else if (!cyclicFrames(sink, std::max(send, slot - cycle_ns / 4), cycle)) {
        return std::nullopt;
      }
      stepDrives(slot);
      if (!operational) {
        if (!walk.active && cycle + 1 == safe_op_cycles) {
          walk.start(kOp, escs.size(), true);
        } else if (walk.active) {
          if (!alFrame(sink, walk, slot + cycle_ns / 2)) return std::nullopt;
          if (!walk.active) {
            operational = true;
            for (NcAxis& nc : ncs) nc.setOperational(true);
          }
        }
      }
    }
    return frames;
  }

  // Registers as the start-up would have written them (a capture without the start-up).
  void configureDirect(std::size_t s) {
    Esc& esc = escs[s];
    std::size_t f = 0;
    auto fmmu = [&](std::uint32_t logical, std::size_t length, std::uint16_t phys,
                    std::uint8_t type) {
      std::uint8_t* p = &esc.mem[kRegFmmu + kFmmuSize * f++];
      putLe(p, logical, 4);
      putLe(p + 4, length, 2);
      p[7] = 7;
      putLe(p + 8, phys, 2);
      p[11] = type;
      p[12] = 1;
    };
    if (outLen(esc) > 0) fmmu(out_addr[s], outLen(esc), outPhys(esc), 2);
    if (inLen(esc) > 0) fmmu(in_addr[s], inLen(esc), inPhys(esc), 1);
  }

  bool startup(const FrameSink& sink, std::int64_t& t, std::int64_t step_ns) {
    const std::size_t n = escs.size();
    auto next = [&] { t += step_ns; };
    // 1. count the slaves
    std::vector<Datagram> frame{registerDatagram(ecat::kBrd, 0, kRegType, 2)};
    if (!exchange(sink, frame, t)) return false;
    next();
    // 2. station addresses by ring position
    frame.clear();
    for (std::size_t s = 0; s < n; ++s) {
      Datagram dg = registerDatagram(ecat::kApwr, static_cast<std::uint16_t>(-static_cast<int>(s)),
                                     kRegStation, 2);
      putLe(dg.data.data(), kFirstStation + s, 2);
      frame.push_back(std::move(dg));
    }
    if (!exchange(sink, frame, t)) return false;
    next();
    // 3. read each slave's state, 4. INIT with error acknowledge to all, then wait for INIT
    AlWalk walk;
    walk.start(kInit, n, false);
    if (!alFrame(sink, walk, t)) return false;
    next();
    frame.clear();
    Datagram reset = registerDatagram(ecat::kBwr, 0, kRegAlControl, 2);
    putLe(reset.data.data(), kInit | kAlErrorBit, 2);
    frame.push_back(std::move(reset));
    if (!exchange(sink, frame, t)) return false;
    next();
    walk.start(kInit, n, false);
    for (int polls = 0; walk.active && polls < 50; ++polls, next()) {
      if (!alFrame(sink, walk, t)) return false;
    }
    // 5. PRE-OP, 6. sync managers and FMMUs, 7. SAFE-OP
    walk.start(kPreOp, n, true);
    for (int polls = 0; walk.active && polls < 50; ++polls, next()) {
      if (!alFrame(sink, walk, t)) return false;
    }
    if (!configFrame(sink, true, t)) return false;
    next();
    if (!configFrame(sink, false, t)) return false;
    next();
    walk.start(kSafeOp, n, true);
    if (esm001_slave >= 0) walk.first_request[static_cast<std::size_t>(esm001_slave)] = kOp;
    for (int polls = 0; walk.active && polls < 50; ++polls, next()) {
      if (!alFrame(sink, walk, t)) return false;
    }
    stepDrives(t);  // the drives' first inputs, for the first cycle
    t = (t / cycle_ns + 1) * cycle_ns;
    return true;
  }
};

Simulator::Simulator(const SimOptions& options) : impl_(std::make_unique<Impl>(options)) {}
Simulator::~Simulator() = default;

const std::vector<SimAxisLayout>& Simulator::layout() const {
  return impl_->axis_layout;
}

std::string Simulator::layoutConfig() const {
  std::vector<AxisConfig> axes;
  for (const SimAxisLayout& a : impl_->axis_layout) {
    AxisConfig axis;
    axis.name = a.name;
    axis.outputs = a.outputs;
    axis.inputs = a.inputs;
    axis.station = a.station;
    axes.push_back(std::move(axis));
  }
  return fmt::format(
             "# The layout of `ncservo simulate` ({} axes, {} layout, {} terminals), for\n"
             "# `ncservo validate --config` or the Wireshark preference ncservo.config.\n",
             impl_->o.axes, impl_->o.layout == LayoutKind::Default ? "default" : "interleaved",
             impl_->o.io_slaves) +
         writeConfig(axes, impl_->o.ready_mode);
}

std::string Simulator::eni() const {
  const Impl& s = *impl_;
  std::vector<EniSlave> slaves;
  for (std::size_t pos = 0; pos < s.escs.size(); ++pos) {
    const Esc& esc = s.escs[pos];
    EniSlave e;
    e.name = esc.kind == SlaveKind::Servo            ? fmt::format("axis{}", esc.axis)
             : esc.kind == SlaveKind::OutputTerminal ? fmt::format("Term {} (EL2008)", pos)
                                                     : fmt::format("Term {} (EL1008)", pos);
    e.station = static_cast<std::uint16_t>(kFirstStation + pos);
    e.position = static_cast<std::uint16_t>(pos);
    e.outputs = s.out_addr[pos];
    e.output_bytes = static_cast<std::uint16_t>(Impl::outLen(esc));
    e.inputs = s.in_addr[pos];
    e.input_bytes = static_cast<std::uint16_t>(Impl::inLen(esc));
    slaves.push_back(std::move(e));
  }
  std::vector<EniCyclicCommand> commands;
  for (const FrameGroup& g : s.groups) {
    std::uint16_t wkc = 0;
    for (int pos : g.slaves) {
      const Esc& esc = s.escs[static_cast<std::size_t>(pos)];
      wkc = static_cast<std::uint16_t>(wkc + (Impl::inLen(esc) > 0 ? 1 : 0) +
                                       (Impl::outLen(esc) > 0 ? 2 : 0));
    }
    commands.push_back({g.base, static_cast<std::uint16_t>(g.size), wkc});
  }
  return writeEni(slaves, commands, static_cast<std::uint32_t>(s.o.cycle_us));
}

std::optional<std::uint64_t> Simulator::run(const FrameSink& sink) {
  return impl_->run(sink);
}

}  // namespace ncservo::sim
