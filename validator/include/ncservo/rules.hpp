// The rule catalogue of RULES.md as one table: ID, slug, severity, party, spec clause, timeout
// and how the rule is checked. The validator, the CLI's `rules` listing, the plugin's expert
// items and the report formats are all generated from it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/config.hpp"

namespace ncservo {

enum class Severity : std::uint8_t { Info, Warning, Error };
const char* severityName(Severity severity);
std::optional<Severity> severityFromName(std::string_view name);

enum class Party : std::uint8_t { Nc, Drive, Bus };
const char* partyName(Party party);

// RULES.md "Time": the configurable timeouts, in milliseconds.
enum class Timeout : std::uint8_t {
  DriveResponse,
  NcRelease,
  EnableResponse,
  ClearResponse,
  FaultReaction,
  ParamTable,
};
struct TimeoutDef {
  Timeout id;
  const char* name;  // the [timeouts] key and --timeout NAME
  std::uint32_t default_ms;
};
inline constexpr std::array<TimeoutDef, 6> kTimeouts{{
    {Timeout::DriveResponse, "drive_response", 20},
    {Timeout::NcRelease, "nc_release", 50},
    {Timeout::EnableResponse, "enable_response", 100},
    {Timeout::ClearResponse, "clear_response", 100},
    {Timeout::FaultReaction, "fault_reaction", 100},
    {Timeout::ParamTable, "param_table", 50},
}};
std::optional<Timeout> timeoutFromName(std::string_view name);

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
  Esm001,
  Esm002,
  Esm003,
  Esm004,
};
inline constexpr std::size_t kRuleCount = 29;

class AxisModel;
struct RuleSettings;

// How a rule is checked. An axis condition is evaluated on every frame that carries the axis; it
// is reported when it begins, or — for a delayed rule — once it has held longer than its timeout.
// Bus rules are reported by the bus model when the event happens.
using AxisCheck = bool (*)(const AxisModel& axis, const RuleSettings& settings);
// What was seen and what was expected; `held_ns` is how long the condition has held.
using AxisDescribe = std::string (*)(const AxisModel& axis, const RuleSettings& settings,
                                     std::int64_t held_ns);

struct RuleDef {
  RuleId id;
  const char* code;  // stable ID, e.g. "SE-001"
  const char* slug;  // e.g. "illegal-enable-edge"
  Severity severity;
  Party party;
  const char* clause;              // where the protocol says so
  std::optional<Timeout> timeout;  // the timeout the rule uses (RULES.md "Time")
  bool delayed;                    // reported when the condition outlasts the timeout
  AxisCheck check;                 // nullptr for bus rules
  AxisDescribe describe;           // nullptr for bus rules
  const char* summary;             // one line, for `ncservo rules` and the expert item
};

// Defined in rules.cpp, next to the checks the table names.
extern const std::array<RuleDef, kRuleCount> kRules;

const RuleDef& ruleDef(RuleId id);
const RuleDef* ruleByCode(std::string_view code);
// "ncservo.rule.illegal_enable_edge"
std::string ruleFilterName(const RuleDef& rule);

// What the user may change: RULES.md defaults, then the config file, then the command line.
struct RuleSettings {
  std::array<bool, kRuleCount> enabled{};
  std::array<Severity, kRuleCount> severity{};
  std::array<std::int64_t, kTimeouts.size()> timeout_ns{};
  std::optional<int> servo_ready_mode;              // global; per axis in axis_ready_mode
  std::vector<std::optional<int>> axis_ready_mode;  // by axis index (configured axes)
  std::uint32_t telegram_failure_limit = 3;

  RuleSettings();
  bool isEnabled(RuleId id) const { return enabled[static_cast<std::size_t>(id)]; }
  Severity severityOf(RuleId id) const { return severity[static_cast<std::size_t>(id)]; }
  std::int64_t timeoutNs(Timeout t) const { return timeout_ns[static_cast<std::size_t>(t)]; }
  std::optional<int> readyModeFor(std::size_t axis) const;

  // Each returns an error message naming what was wrong, or nothing.
  std::optional<std::string> disable(std::string_view code);
  std::optional<std::string> setSeverity(std::string_view code, std::string_view level);
  std::optional<std::string> setTimeout(std::string_view name, std::int64_t ms);
  // Applies a configuration file (already validated by the parser except for rule IDs).
  std::optional<std::string> apply(const Config& config);
};

}  // namespace ncservo
