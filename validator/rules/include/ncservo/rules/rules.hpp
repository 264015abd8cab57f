// The rule catalogue (docs/rules.md) as one table: ID, slug, severity, party, clause, timeout,
// limit and how the rule is checked. The validator, the CLI's `rules` listing, the plugin's expert
// items and the report formats are all generated from it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/model/bus_events.hpp"
#include "ncservo/protocol/fields.hpp"
#include "ncservo/protocol/reads.hpp"

namespace ncservo {

enum class Severity : std::uint8_t { Info, Warning, Error };
const char* severityName(Severity severity);
std::optional<Severity> severityFromName(std::string_view name);

enum class Party : std::uint8_t { Nc, Drive, Bus };
const char* partyName(Party party);

// The timeouts, in milliseconds (docs/configuration.md#timeouts). `capture_pause` is no rule's: a
// forward jump of the timestamps longer than it starts a new segment (docs/protocol.md §8).
enum class Timeout : std::uint8_t {
  DriveResponse,
  NcRelease,
  EnableResponse,
  ClearResponse,
  FaultReaction,
  ParamTable,
  CapturePause,
};
struct TimeoutDef {
  Timeout id;
  const char* name;  // the [timeouts] key and --timeout NAME
  std::uint32_t default_ms;
};
inline constexpr std::array<TimeoutDef, 7> kTimeouts{{
    {Timeout::DriveResponse, "drive_response", 20},
    {Timeout::NcRelease, "nc_release", 50},
    {Timeout::EnableResponse, "enable_response", 100},
    {Timeout::ClearResponse, "clear_response", 100},
    {Timeout::FaultReaction, "fault_reaction", 100},
    {Timeout::ParamTable, "param_table", 50},
    {Timeout::CapturePause, "capture_pause", 1000},
}};
std::optional<Timeout> timeoutFromName(std::string_view name);
// "drive_response, nc_release, ...": the names a configuration and --timeout accept.
std::string timeoutNameList();
// "unknown timeout 'X' (known: ...)", with the closest name.
std::string unknownTimeoutMessage(std::string_view name);
// The longest timeout a user may set, in milliseconds (an hour).
inline constexpr std::uint32_t kMaxTimeoutMs = 3'600'000;

enum class RuleId : std::uint8_t {
  Se001,
  Se002,
  Se003,
  Se004,
  Zp001,
  Zp002,
  Zp003,
  Ec001,
  Ec002,
  Ec003,
  Ec004,
  Sew001,
  Sew002,
  Sew003,
  Ssw001,
  Scw001,
  Rdy001,
  Flt001,
  Pt001,
  Msg001,
  Com001,
  Com002,
  Com003,
  Com004,
  Com005,
  Com006,
  Com007,
  Esm001,
  Esm002,
  Esm003,
  Esm004,
  Mbx001,
  Mbx002,
  Mbx003,
  Erh001,
  Erh002,
  Lnk001,
  Lnk002,
  Dc001,
};
inline constexpr std::size_t kRuleCount = 39;

// docs/rules.md#com-006, COM-007, DC-001: the limits of the rules whose right value depends on the
// machine. A rule's row names the limit it uses (RuleDef::limit).
enum class Limit : std::uint8_t { CycleJitterPercent, ReturnLatencyUs, DcSyncLimitNs };
struct LimitDef {
  Limit id;
  const char* name;  // the configuration key and --limit NAME
  std::uint32_t default_value;
  std::uint32_t min, max;
  const char* unit;
  const char* bounds;  // what it bounds, for docs and errors
};
inline constexpr std::array<LimitDef, 3> kLimits{{
    {.id = Limit::CycleJitterPercent,
     .name = "cycle_jitter_percent",
     .default_value = 10,
     .min = 1,
     .max = 100,
     .unit = "% of the nominal cycle",
     .bounds = "how far a master copy's interval may deviate from the nominal cycle"},
    {.id = Limit::ReturnLatencyUs,
     .name = "return_latency_us",
     .default_value = 500,
     .min = 1,
     .max = 1'000'000,
     .unit = "µs",
     .bounds = "how long after its master copy a returned copy may arrive"},
    {.id = Limit::DcSyncLimitNs,
     .name = "dc_sync_limit_ns",
     .default_value = 1000,
     .min = 1,
     .max = 1'000'000'000,
     .unit = "ns",
     .bounds = "how far a slave's system time difference (0x092C) may be from the reference"},
}};
const LimitDef* limitByName(std::string_view name);

class AxisModel;
struct RuleSettings;

// The index in BusEventData of an event kind, as RuleDef::event names it.
inline constexpr std::size_t kNoEvent = std::variant_size_v<BusEventData>;
template <class Event, std::size_t I = 0>
constexpr std::size_t eventIndex() {
  static_assert(I < kNoEvent, "not a BusEventData alternative");
  if constexpr (std::is_same_v<Event, std::variant_alternative_t<I, BusEventData>>) {
    return I;
  } else {
    return eventIndex<Event, I + 1>();
  }
}

// Where a rule is judged: on one axis's model, on what the bus model saw (working counters,
// cycles) or on what a slave's state machine did (AL control and status).
enum class RuleKind : std::uint8_t { Axis, Bus, Slave };
// Whether a rule runs unless disabled, or only when enabled (`--enable`, `[rules] enable`):
// off where the right limit depends on the machine.
enum class ByDefault : std::uint8_t { On, Off };
const char* ruleKindName(RuleKind kind);

// The rules judged once per run of measurements beyond their limit (COM-006, COM-007): for each
// cyclic frame, whether its last measurement was beyond the rule's limit. A capture segment
// starts with none.
class MeasurementRuns {
 public:
  bool& inRun(RuleId rule, CyclicFrameId frame);
  void clear() { slots_ = {}; }

 private:
  struct Slot {
    std::uint32_t serial = 0;  // of the frame it holds (0: none)
    std::array<bool, kRuleCount> in_run{};
  };
  std::array<Slot, kMaxCyclicFrames> slots_{};
};

// What a check looks at: the axis's model (axis rules) or one event of the bus and slave models,
// with the runs a measurement continues.
struct RuleSubject {
  const AxisModel* axis = nullptr;
  const BusEvent* event = nullptr;
  MeasurementRuns* runs = nullptr;
};
struct RuleDef;
// The row of the rule judging, and the settings as that row reads them: a check and its text
// take the timeout and the limit their row names, never another's (the row is the whole rule).
struct RuleContext {
  const RuleDef& rule;
  const RuleSettings& settings;
  std::int64_t timeoutNs() const;  // the row's timeout as set; the row must name one
  std::int64_t timeoutMs() const;
  std::uint32_t limit() const;  // the row's limit as set; the row must name one
};
// Whether the rule's condition holds. An axis condition is evaluated on every frame that changes
// what it reads; it is reported when it begins or, for a delayed rule, once it has held longer
// than its timeout. An event condition is reported on the frame of the event; for a measurement,
// the condition is that a run beyond the limit begins.
using RuleCheck = bool (*)(const RuleSubject& subject, const RuleContext& context);
// What was seen and what was expected; `held_ns` is how long the condition has held.
using RuleDescribe = std::string (*)(const RuleSubject& subject, const RuleContext& context,
                                     std::int64_t held_ns);
// Where an axis rule's condition began, for a rule whose condition is about a stamped event (an
// emergency, a fault, a read of the drive's history) rather than the frame it is first seen on:
// the validator times it from there, and a new event after a reported one is a new episode.
using RuleBegan = std::optional<Stamp> (*)(const RuleSubject& subject);

// What a rule's timeout is to it (docs/timing.md#rule-time).
enum class TimeoutUse : std::uint8_t {
  None,      // the rule has no timeout
  Delay,     // reported once the condition has held longer than the timeout
  LookBack,  // the condition is an edge that nothing answered within the timeout before it
  Around,    // the condition is an event that nothing answered within the timeout before or
             // after it: reported once the timeout has passed after it
};

struct RuleDef {
  RuleId id;
  const char* code;  // stable ID, e.g. "SE-001"
  const char* slug;  // e.g. "illegal-enable-edge"
  Severity severity;
  Party party;
  RuleKind kind;
  const char* clause;                             // where the protocol says so
  std::optional<Timeout> timeout = std::nullopt;  // the timeout the rule uses (docs/rules.md)
  TimeoutUse timeout_use = TimeoutUse::None;      // what the timeout is to it
  std::optional<Limit> limit = std::nullopt;      // the limit the rule uses (docs/rules.md)
  // When the finding is reported, where that is not on the frame where the condition begins (an
  // axis rule's) or of the event (a bus or slave rule's); `rules --explain` says it.
  const char* reported = nullptr;
  ByDefault by_default = ByDefault::On;
  Reads reads{};                 // axis rules: what check and describe read of the axis
  std::size_t event = kNoEvent;  // bus and slave rules: the BusEventData alternative judged
  RuleCheck check;
  RuleDescribe describe;
  RuleBegan began = nullptr;  // axis rules about a stamped event only
  const char* summary;        // one line, for `ncservo rules` and the expert item

  // Judged once its timeout has passed after the condition began.
  bool delayed() const {
    return timeout_use == TimeoutUse::Delay || timeout_use == TimeoutUse::Around;
  }
};

// Defined in rules.cpp, next to the checks the table names.
extern const std::array<RuleDef, kRuleCount> kRules;

const RuleDef& ruleDef(RuleId id);
// The rule of an ID in any case ("se-001" is SE-001), or null.
const RuleDef* ruleByCode(std::string_view code);
// As ruleByCode; the error names the ID and the closest one ("did you mean").
Result<const RuleDef*> findRule(std::string_view code);
// "ncservo.rule.illegal_enable_edge"
std::string ruleFilterName(const RuleDef& rule);

// The window a rule's timeout allows, in ns from where its condition began: the timeout after it
// for a delay, before it for a look-back, both for an event answered around it; none for a rule
// without a timeout.
struct AllowedWindow {
  std::int64_t from_ns;
  std::int64_t to_ns;
};
std::optional<AllowedWindow> allowedWindow(const RuleDef& rule, const RuleSettings& settings);

// A bus or slave rule's finding on an event, before the user's severities are applied.
struct EventFinding {
  RuleId rule{};
  SlaveRef slave;  // the slave it is about, for slave rules
  std::string message;
};
// The enabled bus and slave rules that fire on the event, in table order; `runs` carries the
// runs of measurements from one event to the next.
void judgeEvent(const BusEvent& event, const RuleSettings& settings, MeasurementRuns& runs,
                std::vector<EventFinding>& out);

// What the user may change: the defaults, then the config file, then the command line.
struct RuleSettings {
  std::array<bool, kRuleCount> enabled{};
  std::array<Severity, kRuleCount> severity{};
  std::array<std::int64_t, kTimeouts.size()> timeout_ns{};
  std::optional<int> servo_ready_mode;              // global; per axis in axis_ready_mode
  std::vector<std::optional<int>> axis_ready_mode;  // by axis index (configured axes)
  std::uint32_t telegram_failure_limit = 3;
  std::array<std::uint32_t, kLimits.size()> limit{};
  // docs/timing.md "Distributed clocks": a slave's DC settled once every later 0x092C read stayed
  // within this many ns.
  std::int64_t dc_settled_ns = 100;

  RuleSettings();
  bool isEnabled(RuleId id) const { return enabled[static_cast<std::size_t>(id)]; }
  Severity severityOf(RuleId id) const { return severity[static_cast<std::size_t>(id)]; }
  std::int64_t timeoutNs(Timeout t) const { return timeout_ns[static_cast<std::size_t>(t)]; }
  std::optional<int> readyModeFor(std::size_t axis) const;
  std::uint32_t limitOf(Limit l) const { return limit[static_cast<std::size_t>(l)]; }

  // Each fails with a message naming what was wrong.
  Status disable(std::string_view code);
  Status enable(std::string_view code);
  Status setLimit(std::string_view name, std::int64_t value);
  Status setSeverity(std::string_view code, std::string_view level);
  Status setTimeout(std::string_view name, std::int64_t ms);
};

inline std::int64_t RuleContext::timeoutNs() const {
  return settings.timeoutNs(rule.timeout.value());
}
inline std::int64_t RuleContext::timeoutMs() const {
  return timeoutNs() / 1'000'000;
}
inline std::uint32_t RuleContext::limit() const {
  return settings.limitOf(rule.limit.value());
}

}  // namespace ncservo
