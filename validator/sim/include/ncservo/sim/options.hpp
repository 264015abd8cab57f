// What `ncservo simulate` is asked for: scenario, set-up, image style, probe, faults; the frames it
// gives and the layout it reports. Parsed and checked here, used by every part of the simulator.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/rules/rules.hpp"
#include "ncservo/sim/capture_shapes.hpp"
#include "ncservo/sim/faults.hpp"

namespace ncservo::sim {

enum class Scenario : std::uint8_t { Commissioning, Faults, Soak, Incidents };
// How the master lays out the process image (docs/protocol.md §9.4).
enum class ImageStyle : std::uint8_t {
  Soem,      // one LRW per frame: all outputs, then all inputs, in ring order
  EtherLab,  // one LRW per frame: per slave in ring order, its outputs, then its inputs
  Mixed,     // one LRW among terminals and drives of other sizes, in either order (by the seed)
  TwinCat,   // an output area written by LWRs and an input area read by LRDs, apart
};
struct ImageStyleName {
  const char* name;
  ImageStyle style;
  const char* layout_alias;  // `--layout`'s older name, or null
  const char* summary;
};
inline constexpr ImageStyleName kImageStyles[] = {
    {.name = "soem",
     .style = ImageStyle::Soem,
     .layout_alias = "default",
     .summary = "one LRW, all outputs then all inputs"},
    {.name = "etherlab",
     .style = ImageStyle::EtherLab,
     .layout_alias = "interleaved",
     .summary = "one LRW, per slave its outputs then inputs"},
    {.name = "mixed",
     .style = ImageStyle::Mixed,
     .layout_alias = nullptr,
     .summary =
         "one LRW among terminals and drives of other sizes, set-up and order drawn from the seed"},
    {.name = "twincat",
     .style = ImageStyle::TwinCat,
     .layout_alias = nullptr,
     .summary = "LWRs of an output area, LRDs of an input area apart, a BRD of the AL status"},
};
// By its name or its `--layout` alias.
std::optional<ImageStyle> imageStyleFromName(std::string_view name);
const ImageStyleName& imageStyleRow(ImageStyle style);

// How often the terminals' inputs change (--io-inputs).
enum class TerminalInputs : std::uint8_t {
  Slow,        // counters and triangles that step every 50 ms
  EveryCycle,  // values that change every cycle, drawn from the cycle and the slave
};
struct TerminalInputsName {
  const char* name;
  TerminalInputs inputs;
  const char* summary;
};
inline constexpr TerminalInputsName kTerminalInputs[] = {
    {.name = "slow",
     .inputs = TerminalInputs::Slow,
     .summary = "counters and triangles stepping every 50 ms"},
    {.name = "cycle",
     .inputs = TerminalInputs::EveryCycle,
     .summary = "values that change every cycle, as busy inputs do"},
};

// Where a capture that begins in the middle of a commissioning session begins (--start-in):
// the capture drops every frame before that moment, the start-up included. InFault (`fault:RULE`,
// no row below) begins inside the standing condition of that rule's --fault.
enum class MidStart : std::uint8_t { None, Homing, Fault, ErrorClear, InFault };
struct MidStartName {
  const char* name;
  MidStart start;
  double after_plan_s;  // the moment, from the start of the plan (axis 1 faults 0.8 s into it)
  const char* summary;
};
inline constexpr MidStartName kMidStarts[] = {
    {.name = "homing",
     .start = MidStart::Homing,
     .after_plan_s = 0.31,
     .summary = "during the odd axes' zero-pulse search"},
    {.name = "fault",
     .start = MidStart::Fault,
     .after_plan_s = 0.81,
     .summary = "while axis 1's drive fault stands, before its error clear"},
    {.name = "error-clear",
     .start = MidStart::ErrorClear,
     .after_plan_s = 0.827,
     .summary = "during axis 1's error-clear handshake"},
};
std::optional<MidStart> midStartFromName(std::string_view name);
const MidStartName& midStartRow(MidStart start);
// --start-in NAME or fault:RULE.
struct MidStartRequest {
  MidStart start = MidStart::None;
  std::optional<RuleId> fault;  // InFault: the rule whose --fault the capture begins inside
};
// The request, or an error naming the moments and the rules a capture can begin inside.
Result<MidStartRequest> parseMidStart(std::string_view text);
// The rules whose fault has a standing condition a capture can begin inside (the recipe rows
// with a standing time), "SE-003, FLT-001".
std::string standingFaultRules();

// A probe in the line between the master and the first slave.
enum class Probe : std::uint8_t {
  None,
  Esl,  // an ET2000: each frame behind a 16-byte ESL header with its own exact timestamp
};

std::optional<Scenario> scenarioFromName(std::string_view name);
const char* scenarioName(Scenario scenario);

// --fault RULE[@SECONDS][:AXIS]
struct FaultRequest {
  RuleId rule{};
  std::optional<double> at_s;  // capture time; default: the scenario's quiet time
  std::optional<int> axis;     // default: an axis that suits the rule
  std::string text;            // as given, for messages
};
// The fault, or an error saying what is wrong with the text.
Result<FaultRequest> parseFault(std::string_view text);

// --late-cycle SECONDS:US (the first cycle at or after SECONDS sent US late) and
// --lost-cycles SECONDS:N (N cycles from the first at or after SECONDS not sent).
struct CycleDisturbance {
  double at_s = 0;
  int amount = 0;
  std::string text;  // as given, for messages
};
Result<CycleDisturbance> parseCycleDisturbance(std::string_view option, std::string_view text);

// The station address the master gives the first slave of the ring; the others count up.
inline constexpr std::uint16_t kFirstStation = 0x03E9;

// --bad-link STATION:PORT@SECONDS[xFRAMES]: from SECONDS on, the next FRAMES frames (default 2)
// that cross the cable at the slave's port reach the slave behind it corrupted
// (docs/simulate.md#diagnosis).
struct BadLink {
  std::uint16_t station = 0;
  std::uint8_t port = 0;
  double at_s = 0;
  int frames = 2;
  std::string text;  // as given, for messages
};
Result<BadLink> parseBadLink(std::string_view text);
// --sync-error STATION@SECONDS: the slave falls from OP to SAFE-OP with AL status code 0x001A
// (synchronization error) at SECONDS; the master's AL status poll sees it, acknowledges it and
// walks the slave back to OP (docs/simulate.md#diagnosis).
struct SlaveAt {
  std::uint16_t station = 0;
  double at_s = 0;
  std::string text;  // as given, for messages
};
Result<SlaveAt> parseSyncError(std::string_view text);

struct SimOptions {
  Scenario scenario = Scenario::Commissioning;
  int axes = 4;                      // servos, 1..32
  std::optional<int> io_slaves;      // other slaves sharing the image, 0..32 (default per style)
  int cycle_us = 1000;               // 125..10000
  std::optional<double> duration_s;  // default per scenario
  std::uint64_t seed = 1;
  ImageStyle image = ImageStyle::Soem;
  Probe probe = Probe::None;
  bool startup = true;
  int ready_mode = 0;       // the drives' Servo_Ready_Mode
  int jitter_us = 0;        // master send jitter, at most a quarter cycle
  double dc_drift_ppm = 0;  // the reference clock's rate against the master's, -1000..1000
  double loss = 0;          // probability that a returned frame is lost after the slaves
  int latency_us = 0;  // returned copy this long after its master copy (0: the ring's own delay)
  double capture_loss = 0;  // probability that the capture misses a cycle's master copies
  std::vector<CycleDisturbance> late_cycles;
  std::vector<CycleDisturbance> lost_cycles;
  std::vector<FaultRequest> faults;
  // What the drives and the ESCs say besides the process data (docs/simulate.md#diagnosis): the
  // servos' mailboxes, the drives' emergencies and error history, the NC's reads of it after a
  // fault, the master's polls of the error counters, AL status and system time differences.
  bool diagnosis = false;
  std::vector<BadLink> bad_links;
  std::vector<SlaveAt> sync_errors;
  // Shapes of a machine's bus (docs/simulate.md#shapes); the defaults add none.
  TerminalInputs terminal_inputs = TerminalInputs::Slow;
  int cia402_drives = 0;  // neighbours of another protocol with 10/40-byte PDOs, 0..32
  double idle_s = 0;      // the NC enables nothing for this long after the start-up
  bool idle_all = false;  // ... or for the whole capture
  MidStart mid_start = MidStart::None;
  std::optional<RuleId> mid_start_fault;  // MidStart::InFault: the --fault it begins inside
  int io_task_us = 0;  // the terminals in a frame of their own at this cycle (0: none)
  // What the capturing PC does to the recording (docs/simulate.md#the-capturing-pc); the
  // defaults do nothing.
  StampShaping capture_stamps;
  bool duplicate_records = false;  // every record twice, as a mirroring switch port gives it
  bool second_interface = false;   // the PC's office port as a second interface (pcapng only)
  bool writes_pcapng = false;      // the capture is a pcapng (the CLI says, from --format)
};

// This simulator's set-up: the odd axes have an incremental encoder (zero-pulse search), the even
// ones an absolute encoder.
inline bool isIncrementalAxis(int axis) {
  return axis % 2 == 1;
}
// The NC's plan starts this long after the capture's start, once the start-up is over.
inline constexpr double kStartupSeconds = 0.2;

// The other slaves a style has when --io-slaves does not say.
int defaultIoSlaves(ImageStyle style);
// The default duration of a scenario, in seconds.
double defaultDuration(Scenario scenario);
// Checks the options and resolves defaults (fault times and axes); an error is the message for
// the user.
Status resolveOptions(SimOptions& options);

struct SimFrame {
  std::int64_t time_ns;  // since the Unix epoch: the capturing PC's stamp
  const std::uint8_t* data;
  std::size_t size;
  bool returned = false;           // the copy the ring returned (else the master's)
  std::uint32_t interface_id = 0;  // the capture's interface: 0 the bus, 1 the office port
};
// Receives each frame in capture order; returns false to stop (e.g. a write error).
using FrameSink = std::function<bool(const SimFrame&)>;

}  // namespace ncservo::sim
