// The rule catalogue (rules.hpp) against a copy written by hand, and the user's settings
// (RuleSettings).
#include "ncservo/rules/rules.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "ncservo/config/config.hpp"
#include "status_text.hpp"

namespace ncservo {
namespace {

// ---- The rule table against a copy written by hand ----

constexpr auto E = Severity::Error;
constexpr auto W = Severity::Warning;
constexpr auto I = Severity::Info;
constexpr auto NC = Party::Nc;
constexpr auto DRIVE = Party::Drive;
constexpr auto BUS = Party::Bus;
constexpr auto AXIS = RuleKind::Axis;
constexpr auto BUSK = RuleKind::Bus;
constexpr auto SLAVE = RuleKind::Slave;
constexpr std::optional<Timeout> kNoTimeout{};
constexpr std::optional<Timeout> kDrive{Timeout::DriveResponse};
constexpr auto NONE = TimeoutUse::None;
constexpr auto DELAY = TimeoutUse::Delay;
constexpr auto BACK = TimeoutUse::LookBack;
constexpr auto AROUND = TimeoutUse::Around;

struct SpecRow {
  const char* code;
  const char* slug;
  Severity severity;
  Party party;
  std::optional<Timeout> timeout;  // the timeout its text names
  // DELAY: "longer than T", reported once the condition outlasts T; BACK: an edge with nothing
  // answering it within T before; AROUND: an event with nothing answering it within T before or
  // after it
  TimeoutUse use;
  RuleKind kind;                         // judged on an axis's model, the bus's events or a slave's
  ByDefault by_default = ByDefault::On;  // "off by default" in its text: run only when enabled
  std::optional<Limit> limit{};          // the limit its text names
};

// The catalogue written by hand, table by table.
// clang-format off
const SpecRow kSpec[] = {
    {"SE-001", "illegal-enable-edge", E, NC, kNoTimeout, NONE, AXIS},
    {"SE-002", "enable-without-edge", E, DRIVE, kDrive, BACK, AXIS},
    {"SE-003", "not-disabled", E, DRIVE, kDrive, DELAY, AXIS},
    {"SE-004", "enable-not-honoured", W, DRIVE, Timeout::EnableResponse, DELAY, AXIS},
    {"ZP-001", "zpulse-ack-not-cleared", E, DRIVE, kDrive, DELAY, AXIS},
    {"ZP-002", "zpulse-ack-without-request", E, DRIVE, kDrive, BACK, AXIS},
    {"ZP-003", "zpulse-absolute-encoder", W, NC, kNoTimeout, NONE, AXIS},
    {"EC-001", "clear-ack-without-request", E, DRIVE, kDrive, BACK, AXIS},
    {"EC-002", "clear-request-held", W, NC, Timeout::NcRelease, DELAY, AXIS},
    {"EC-003", "clear-ack-not-cleared", E, DRIVE, kDrive, DELAY, AXIS},
    {"EC-004", "clear-not-acknowledged", W, DRIVE, Timeout::ClearResponse, DELAY, AXIS},
    {"SEW-001", "cause-without-summary", E, DRIVE, kNoTimeout, NONE, AXIS},
    {"SEW-002", "summary-without-cause", W, DRIVE, kDrive, DELAY, AXIS},
    {"SEW-003", "reserved-error-bits", W, DRIVE, kNoTimeout, NONE, AXIS},
    {"SSW-001", "reserved-status-bits", W, DRIVE, kNoTimeout, NONE, AXIS},
    {"SCW-001", "reserved-control-bits", W, NC, kNoTimeout, NONE, AXIS},
    {"RDY-001", "ready-mismatch", E, DRIVE, kDrive, DELAY, AXIS},
    {"FLT-001", "enabled-with-error", E, DRIVE, Timeout::FaultReaction, DELAY, AXIS},
    {"PT-001", "param-table-not-followed", W, DRIVE, Timeout::ParamTable, DELAY, AXIS},
    {"MSG-001", "undefined-message-code", W, DRIVE, kNoTimeout, NONE, AXIS},
    {"COM-001", "working-counter", E, BUS, kNoTimeout, NONE, BUSK},
    {"COM-002", "cycle-gap", W, BUS, kNoTimeout, NONE, BUSK},
    {"COM-003", "timeout-not-reported", I, DRIVE, kDrive, DELAY, AXIS},
    {"COM-004", "frame-not-returned", W, BUS, kNoTimeout, NONE, BUSK},
    {"COM-005", "telegram-failure-limit", E, BUS, kNoTimeout, NONE, AXIS},
    {"COM-006", "cycle-jitter", W, BUS, kNoTimeout, NONE, BUSK, ByDefault::Off,
     Limit::CycleJitterPercent},
    {"COM-007", "late-return", W, BUS, kNoTimeout, NONE, BUSK, ByDefault::Off,
     Limit::ReturnLatencyUs},
    {"ESM-001", "invalid-al-transition", E, NC, kNoTimeout, NONE, SLAVE},
    {"ESM-002", "pdo-outside-op", W, NC, kNoTimeout, NONE, AXIS},
    {"ESM-003", "al-error", E, DRIVE, kNoTimeout, NONE, SLAVE},
    {"ESM-004", "al-error-at-init", I, DRIVE, kNoTimeout, NONE, SLAVE},
    // What the drives and the ESCs say themselves
    {"MBX-001", "emergency-without-fault", W, DRIVE, kDrive, AROUND, AXIS},
    {"MBX-002", "fault-without-emergency", I, DRIVE, kDrive, AROUND, AXIS},
    {"MBX-003", "sdo-abort", I, DRIVE, kNoTimeout, NONE, SLAVE},
    {"ERH-001", "error-history-shrunk", W, DRIVE, kNoTimeout, NONE, SLAVE},
    {"ERH-002", "error-history-disagrees", I, DRIVE, kNoTimeout, NONE, AXIS},
    {"LNK-001", "link-rx-errors", W, BUS, kNoTimeout, NONE, SLAVE},
    {"LNK-002", "link-lost", E, BUS, kNoTimeout, NONE, SLAVE},
    {"DC-001", "dc-out-of-sync", W, BUS, kNoTimeout, NONE, SLAVE, ByDefault::On,
     Limit::DcSyncLimitNs},
};
// clang-format on

TEST(RuleTable, MatchesRulesMdRowByRow) {
  ASSERT_EQ(std::size(kSpec), kRuleCount);
  ASSERT_EQ(kRules.size(), kRuleCount);
  for (std::size_t i = 0; i < kRuleCount; ++i) {
    const SpecRow& spec = kSpec[i];
    const RuleDef& rule = kRules[i];
    SCOPED_TRACE(spec.code);
    EXPECT_EQ(static_cast<std::size_t>(rule.id), i) << "IDs in enum order";
    EXPECT_EQ(&ruleDef(rule.id), &rule);
    EXPECT_STREQ(rule.code, spec.code);
    EXPECT_STREQ(rule.slug, spec.slug);
    EXPECT_EQ(rule.severity, spec.severity);
    EXPECT_EQ(rule.party, spec.party);
    EXPECT_EQ(rule.timeout, spec.timeout);
    EXPECT_EQ(rule.timeout_use, spec.use);
    EXPECT_EQ(rule.limit, spec.limit);
    EXPECT_EQ(rule.kind, spec.kind);
    EXPECT_EQ(rule.by_default, spec.by_default);
    EXPECT_NE(rule.check, nullptr) << "every rule is a row with its check";
    EXPECT_NE(rule.describe, nullptr);
    EXPECT_NE(rule.clause, nullptr);
    EXPECT_NE(rule.summary, nullptr);
    if (rule.summary != nullptr) {
      EXPECT_GT(std::string(rule.summary).size(), 10u);
    }
  }
}

TEST(RuleTable, CodesAndSlugsAreUniqueAndWellFormed) {
  std::set<std::string> codes, slugs, filters;
  for (const RuleDef& rule : kRules) {
    SCOPED_TRACE(rule.code);
    EXPECT_TRUE(codes.insert(rule.code).second) << "duplicate code";
    EXPECT_TRUE(slugs.insert(rule.slug).second) << "duplicate slug";
    EXPECT_TRUE(filters.insert(ruleFilterName(rule)).second) << "duplicate filter name";
    const std::string code = rule.code;
    const std::size_t dash = code.find('-');
    ASSERT_NE(dash, std::string::npos);
    EXPECT_EQ(code.size() - dash - 1, 3u) << "three digits after the dash";
    for (char c : std::string(rule.slug)) {
      EXPECT_TRUE((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-') << rule.slug;
    }
  }
}

TEST(RuleTable, RuleByCodeRoundTrips) {
  for (const RuleDef& rule : kRules) {
    EXPECT_EQ(ruleByCode(rule.code), &rule) << rule.code;
  }
  for (const char* unknown : {"", "SE-000", "SE-005", "SE001", "SE-001 ", "ESM-005"}) {
    EXPECT_EQ(ruleByCode(unknown), nullptr) << "'" << unknown << "'";
  }
}

// IDs are matched in any case; an unknown one is named with the closest ID.
struct FindRuleCase {
  const char* typed;
  std::optional<RuleId> found;  // none: an error
  const char* error;            // a text the error contains
};
const FindRuleCase kFindRuleCases[] = {
    {"SE-001", RuleId::Se001, nullptr},
    {"se-001", RuleId::Se001, nullptr},
    {"Msg-001", RuleId::Msg001, nullptr},
    {"esm-004", RuleId::Esm004, nullptr},
    {"SE-01", std::nullopt,
     "unknown rule ID 'SE-01' (see `ncservo rules`); did you mean 'SE-001'?"},
    {"msg-01", std::nullopt, "did you mean 'MSG-001'?"},
    {"COM-0005", std::nullopt, "did you mean 'COM-005'?"},
    {"XX-999", std::nullopt, "unknown rule ID 'XX-999' (see `ncservo rules`)"},
};

TEST(RuleTable, FindRuleInAnyCase) {
  for (const FindRuleCase& c : kFindRuleCases) {
    SCOPED_TRACE(c.typed);
    const Result<const RuleDef*> rule = findRule(c.typed);
    if (c.found) {
      ASSERT_TRUE(rule.has_value()) << rule.error().text();
      EXPECT_EQ((*rule)->id, *c.found);
    } else {
      ASSERT_FALSE(rule.has_value());
      EXPECT_NE(rule.error().text().find(c.error), std::string::npos) << rule.error().text();
    }
  }
  const Result<const RuleDef*> unknown = findRule("XX-999");
  ASSERT_FALSE(unknown.has_value());
  EXPECT_EQ(unknown.error().text().find("did you mean"), std::string::npos);
}

TEST(RuleTable, FilterNames) {
  EXPECT_EQ(ruleFilterName(ruleDef(RuleId::Se001)), "ncservo.rule.illegal_enable_edge");
  EXPECT_EQ(ruleFilterName(ruleDef(RuleId::Zp002)), "ncservo.rule.zpulse_ack_without_request");
  EXPECT_EQ(ruleFilterName(ruleDef(RuleId::Esm004)), "ncservo.rule.al_error_at_init");
  for (const RuleDef& rule : kRules) {
    std::string expected = std::string("ncservo.rule.") + rule.slug;
    std::replace(expected.begin(), expected.end(), '-', '_');
    EXPECT_EQ(ruleFilterName(rule), expected);
  }
}

TEST(RuleTable, TimedRulesSayWhatTheTimeoutIsAxisRulesCheckAndDescribe) {
  for (const RuleDef& rule : kRules) {
    SCOPED_TRACE(rule.code);
    EXPECT_EQ(rule.timeout.has_value(), rule.timeout_use != TimeoutUse::None)
        << "a row with a timeout says whether it delays the report or bounds a look back";
    if (rule.timeout) {
      EXPECT_NE(rule.timeout, Timeout::CapturePause) << "no rule's";
      EXPECT_EQ(rule.kind, RuleKind::Axis) << "a timed rule is timed per axis";
    }
    EXPECT_NE(rule.check, nullptr);
    EXPECT_NE(rule.describe, nullptr);
    EXPECT_EQ(rule.kind == RuleKind::Axis, rule.reads.any() || rule.id == RuleId::Com005)
        << "an axis rule declares what it reads (COM-005 reads only the failure counter)";
    EXPECT_TRUE(rule.began == nullptr || rule.kind == RuleKind::Axis)
        << "only an axis rule's episode begins at a stamped event";
    EXPECT_EQ(rule.began != nullptr, rule.reads.mailbox)
        << "the rules on what a drive said time it from the message or the fault it answers";
  }
}

// docs/rules.md: the "used by" column of the timeout table (COM-003's text names
// drive_response too).
TEST(RuleTable, TimeoutsAndTheRulesThatUseThem) {
  struct Row {
    const char* name;
    std::uint32_t default_ms;
    std::vector<RuleId> used_by;
  };
  const Row rows[] = {
      {"drive_response",
       20,
       {RuleId::Se002, RuleId::Se003, RuleId::Zp001, RuleId::Zp002, RuleId::Ec001, RuleId::Ec003,
        RuleId::Sew002, RuleId::Rdy001, RuleId::Com003, RuleId::Mbx001, RuleId::Mbx002}},
      {"nc_release", 50, {RuleId::Ec002}},
      {"enable_response", 100, {RuleId::Se004}},
      {"clear_response", 100, {RuleId::Ec004}},
      {"fault_reaction", 100, {RuleId::Flt001}},
      {"param_table", 50, {RuleId::Pt001}},
      {"capture_pause", 1000, {}},
  };
  ASSERT_EQ(std::size(rows), kTimeouts.size());
  for (std::size_t i = 0; i < kTimeouts.size(); ++i) {
    const Row& row = rows[i];
    SCOPED_TRACE(row.name);
    EXPECT_EQ(static_cast<std::size_t>(kTimeouts[i].id), i);
    EXPECT_STREQ(kTimeouts[i].name, row.name);
    EXPECT_EQ(kTimeouts[i].default_ms, row.default_ms);
    EXPECT_EQ(timeoutFromName(row.name), kTimeouts[i].id);
    EXPECT_TRUE(
        parseConfig(std::string("[timeouts]\n") + row.name + " = 5\n", "t.toml").has_value())
        << "the config file accepts it";
    std::vector<RuleId> users;
    for (const RuleDef& rule : kRules) {
      if (rule.timeout == kTimeouts[i].id) users.push_back(rule.id);
    }
    EXPECT_EQ(users, row.used_by);
  }
  EXPECT_FALSE(timeoutFromName("drive-response").has_value());
  EXPECT_FALSE(timeoutFromName("").has_value());
}

TEST(RuleTable, SeverityAndPartyNames) {
  struct Row {
    Severity severity;
    const char* name;
  };
  for (const Row& row : {Row{E, "error"}, Row{W, "warning"}, Row{I, "info"}}) {
    EXPECT_STREQ(severityName(row.severity), row.name);
    EXPECT_EQ(severityFromName(row.name), row.severity);
  }
  for (const char* bad : {"", "Error", "fatal", "never", "warn"}) {
    EXPECT_FALSE(severityFromName(bad).has_value()) << bad;
  }
  EXPECT_STREQ(partyName(NC), "NC");
  EXPECT_STREQ(partyName(DRIVE), "drive");
  EXPECT_STREQ(partyName(BUS), "bus");
}

// ---- RuleSettings ----

TEST(RuleSettings, DefaultsAreRulesMd) {
  const RuleSettings s;
  for (const RuleDef& rule : kRules) {
    EXPECT_EQ(s.isEnabled(rule.id), rule.by_default == ByDefault::On) << rule.code;
    EXPECT_EQ(s.severityOf(rule.id), rule.severity) << rule.code;
  }
  for (const LimitDef& l : kLimits) EXPECT_EQ(s.limitOf(l.id), l.default_value) << l.name;
  for (const TimeoutDef& t : kTimeouts) {
    EXPECT_EQ(s.timeoutNs(t.id), std::int64_t{t.default_ms} * 1'000'000) << t.name;
  }
  EXPECT_EQ(s.telegram_failure_limit, 3u);
  EXPECT_FALSE(s.servo_ready_mode.has_value());
  EXPECT_FALSE(s.readyModeFor(0).has_value());
}

struct DisableCase {
  const char* code;
  std::optional<RuleId> disabled;  // none: rejected
  const char* error;               // a text the error contains
};
const DisableCase kDisableCases[] = {
    {"MSG-001", RuleId::Msg001, nullptr},
    {"ESM-004", RuleId::Esm004, nullptr},
    {"MSG-009", std::nullopt, "unknown rule ID 'MSG-009'"},
    {"msg-001", RuleId::Msg001, nullptr},
    {"MSG-01", std::nullopt,
     "unknown rule ID 'MSG-01' (see `ncservo rules`); did you mean 'MSG-001'?"},
    {"", std::nullopt, "unknown rule ID ''"},
};

TEST(RuleSettings, Disable) {
  for (const DisableCase& c : kDisableCases) {
    SCOPED_TRACE(c.code);
    RuleSettings s;
    const std::optional<std::string> error = test::errorOf(s.disable(c.code));
    for (const RuleDef& rule : kRules) {
      EXPECT_EQ(s.isEnabled(rule.id),
                rule.by_default == ByDefault::On && !(c.disabled && rule.id == *c.disabled))
          << rule.code;
    }
    if (c.disabled) {
      EXPECT_FALSE(error.has_value()) << *error;
    } else {
      ASSERT_TRUE(error.has_value());
      EXPECT_NE(error->find(c.error), std::string::npos) << *error;
    }
  }
}

struct SeverityCase {
  const char* code;
  const char* level;
  std::optional<Severity> set;  // none: rejected
  std::vector<const char*> error;
};
const SeverityCase kSeverityCases[] = {
    {"EC-002", "error", E, {}},
    {"SE-001", "info", I, {}},
    {"COM-003", "warning", W, {}},
    {"SE-001", "error", E, {}},
    {"XX-001", "error", std::nullopt, {"unknown rule ID 'XX-001'"}},
    {"se-001", "warning", W, {}},
    {"EC-02", "error", std::nullopt, {"unknown rule ID 'EC-02'", "did you mean 'EC-002'?"}},
    {"SE-001", "fatal", std::nullopt, {"'fatal'", "SE-001", "error, warning or info"}},
    {"SE-001", "", std::nullopt, {"''", "SE-001"}},
    {"SE-001", "Error", std::nullopt, {"'Error'"}},
};

TEST(RuleSettings, SetSeverity) {
  for (const SeverityCase& c : kSeverityCases) {
    SCOPED_TRACE(std::string(c.code) + " = " + c.level);
    RuleSettings s;
    const std::optional<std::string> error = test::errorOf(s.setSeverity(c.code, c.level));
    const RuleDef* target = ruleByCode(c.code);
    for (const RuleDef& rule : kRules) {
      const bool changed = c.set && &rule == target;
      EXPECT_EQ(s.severityOf(rule.id), changed ? *c.set : rule.severity) << rule.code;
      EXPECT_EQ(s.isEnabled(rule.id), rule.by_default == ByDefault::On);
    }
    if (c.set) {
      EXPECT_FALSE(error.has_value()) << *error;
    } else {
      ASSERT_TRUE(error.has_value());
      for (const char* text : c.error) EXPECT_NE(error->find(text), std::string::npos) << *error;
    }
  }
}

struct TimeoutCase {
  const char* name;
  std::int64_t ms;
  bool ok;
  std::vector<const char*> error;
};
const TimeoutCase kTimeoutCases[] = {
    {"drive_response", 5, true, {}},
    {"param_table", 0, true, {}},
    {"fault_reaction", 3'600'000, true, {}},
    {"fault_reaction", 3'600'001, false, {"fault_reaction", "3600001"}},
    {"nc_release", -1, false, {"nc_release", "-1"}},
    {"drive-response",
     5,
     false,
     {"unknown timeout 'drive-response'", "drive_response, nc_release",
      "did you mean 'drive_response'?"}},
    {"", 5, false, {"unknown timeout ''"}},
};

TEST(RuleSettings, SetTimeout) {
  for (const TimeoutCase& c : kTimeoutCases) {
    SCOPED_TRACE(std::string(c.name) + " = " + std::to_string(c.ms));
    RuleSettings s;
    const std::optional<std::string> error = test::errorOf(s.setTimeout(c.name, c.ms));
    for (const TimeoutDef& t : kTimeouts) {
      const bool changed = c.ok && c.name == std::string(t.name);
      EXPECT_EQ(s.timeoutNs(t.id), (changed ? c.ms : std::int64_t{t.default_ms}) * 1'000'000)
          << t.name;
    }
    if (c.ok) {
      EXPECT_FALSE(error.has_value()) << *error;
    } else {
      ASSERT_TRUE(error.has_value());
      for (const char* text : c.error) EXPECT_NE(error->find(text), std::string::npos) << *error;
    }
  }
}

TEST(RuleSettings, ApplyAConfiguration) {
  Config config;
  config.servo_ready_mode = 1;
  config.telegram_failure_limit = 7;
  config.timeouts_ms = {{"drive_response", 30}, {"clear_response", 250}};
  config.disabled_rules = {"MSG-001", "COM-002"};
  config.enabled_rules = {"COM-006"};
  config.limits = {{"cycle_jitter_percent", 30}};
  config.severity_overrides = {{"EC-002", "error"}, {"COM-003", "warning"}};
  AxisConfig x, y;
  x.servo_ready_mode = 0;
  config.axes = {x, y};

  RuleSettings s;
  const std::optional<std::string> error = test::errorOf(applyConfig(config, s));
  ASSERT_FALSE(error.has_value()) << *error;
  EXPECT_EQ(s.servo_ready_mode, 1);
  EXPECT_EQ(s.telegram_failure_limit, 7u);
  EXPECT_EQ(s.timeoutNs(Timeout::DriveResponse), 30'000'000);
  EXPECT_EQ(s.timeoutNs(Timeout::ClearResponse), 250'000'000);
  EXPECT_EQ(s.timeoutNs(Timeout::NcRelease), 50'000'000) << "untouched";
  EXPECT_FALSE(s.isEnabled(RuleId::Msg001));
  EXPECT_FALSE(s.isEnabled(RuleId::Com002));
  EXPECT_TRUE(s.isEnabled(RuleId::Com001));
  EXPECT_TRUE(s.isEnabled(RuleId::Com006));
  EXPECT_FALSE(s.isEnabled(RuleId::Com007)) << "off by default, not enabled";
  EXPECT_EQ(s.limitOf(Limit::CycleJitterPercent), 30u);
  EXPECT_EQ(s.limitOf(Limit::ReturnLatencyUs), 500u) << "untouched";
  EXPECT_EQ(s.severityOf(RuleId::Ec002), E);
  EXPECT_EQ(s.severityOf(RuleId::Com003), W);
  EXPECT_EQ(s.severityOf(RuleId::Ec001), E);
  // Per axis: the axis's own mode, else the global one.
  EXPECT_EQ(s.readyModeFor(0), 0);
  EXPECT_EQ(s.readyModeFor(1), 1);
  EXPECT_EQ(s.readyModeFor(5), 1);
}

TEST(RuleSettings, ApplyKeepsWhatTheConfigurationDoesNotSet) {
  RuleSettings s;
  ASSERT_TRUE(s.setTimeout("nc_release", 80));
  s.servo_ready_mode = 0;
  ASSERT_TRUE(applyConfig(Config{}, s));
  EXPECT_EQ(s.timeoutNs(Timeout::NcRelease), 80'000'000);
  EXPECT_EQ(s.servo_ready_mode, 0);
  EXPECT_EQ(s.telegram_failure_limit, 3u);
  for (const RuleDef& rule : kRules)
    EXPECT_EQ(s.isEnabled(rule.id), rule.by_default == ByDefault::On);
}

struct EnableCase {
  const char* code;
  std::optional<RuleId> enabled;  // none: rejected
  const char* error;              // a text the error contains
};
const EnableCase kEnableCases[] = {
    {"COM-006", RuleId::Com006, nullptr},
    {"com-007", RuleId::Com007, nullptr},
    {"MSG-001", RuleId::Msg001, nullptr},  // on already: stays on
    {"COM-08", std::nullopt, "unknown rule ID 'COM-08'"},
};

TEST(RuleSettings, Enable) {
  for (const EnableCase& c : kEnableCases) {
    SCOPED_TRACE(c.code);
    RuleSettings s;
    const std::optional<std::string> error = test::errorOf(s.enable(c.code));
    for (const RuleDef& rule : kRules) {
      EXPECT_EQ(s.isEnabled(rule.id),
                rule.by_default == ByDefault::On || (c.enabled && rule.id == *c.enabled))
          << rule.code;
    }
    if (c.enabled) {
      EXPECT_FALSE(error.has_value()) << *error;
    } else {
      ASSERT_TRUE(error.has_value());
      EXPECT_NE(error->find(c.error), std::string::npos) << *error;
    }
  }
}

struct LimitCase {
  const char* name;
  std::int64_t value;
  bool ok;
  std::vector<const char*> error;
};
const LimitCase kLimitCases[] = {
    {"cycle_jitter_percent", 25, true, {}},
    {"cycle_jitter_percent", 1, true, {}},
    {"cycle_jitter_percent", 0, false, {"cycle_jitter_percent = 0", "1 to 100"}},
    {"cycle_jitter_percent", 101, false, {"101"}},
    {"return_latency_us", 1'000'000, true, {}},
    {"return_latency_us", 1'000'001, false, {"return_latency_us", "1000001"}},
    {"return_latency",
     5,
     false,
     {"unknown limit 'return_latency'", "did you mean 'return_latency_us'?"}},
};

TEST(RuleSettings, SetLimit) {
  for (const LimitCase& c : kLimitCases) {
    SCOPED_TRACE(std::string(c.name) + " = " + std::to_string(c.value));
    RuleSettings s;
    const std::optional<std::string> error = test::errorOf(s.setLimit(c.name, c.value));
    for (const LimitDef& l : kLimits) {
      const bool changed = c.ok && c.name == std::string(l.name);
      EXPECT_EQ(s.limitOf(l.id), changed ? static_cast<std::uint32_t>(c.value) : l.default_value)
          << l.name;
    }
    if (c.ok) {
      EXPECT_FALSE(error.has_value()) << *error;
    } else {
      ASSERT_TRUE(error.has_value());
      for (const char* text : c.error) EXPECT_NE(error->find(text), std::string::npos) << *error;
    }
  }
}

TEST(RuleSettings, ApplyRejectsUnknownNamesNamingThem) {
  struct Case {
    const char* name;
    std::function<void(Config&)> edit;
    const char* error;
  };
  const Case cases[] = {
      {"disabled rule",
       [](Config& c) {
         c.disabled_rules = {"MSG-001", "FOO-001"};
       },
       "unknown rule ID 'FOO-001'"},
      {"severity rule",
       [](Config& c) {
         c.severity_overrides = {{"BAR-002", "info"}};
       },
       "unknown rule ID 'BAR-002'"},
      {"severity level",
       [](Config& c) {
         c.severity_overrides = {{"SE-001", "loud"}};
       },
       "severity 'loud' for SE-001"},
      {"timeout value",
       [](Config& c) {
         c.timeouts_ms = {{"param_table", 4'000'000}};
       },
       "timeout param_table = 4000000 ms"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Config config;
    c.edit(config);
    RuleSettings s;
    const std::optional<std::string> error = test::errorOf(applyConfig(config, s));
    ASSERT_TRUE(error.has_value());
    EXPECT_NE(error->find(c.error), std::string::npos) << *error;
  }
}

TEST(RuleSettings, ApplyTheInterfacesExample) {
  const Result<Config> parsed = parseConfig(R"(servo_ready_mode = 0
telegram_failure_limit = 3
[timeouts]
drive_response = 20
[[axis]]
name = "X"
outputs = 0x00010000
inputs  = 0x00010028
servo_ready_mode = 1
[[axis]]
name = "Y"
station = 0x03EA
sm_outputs = 0x1100
sm_inputs  = 0x1180
[rules]
disable = ["MSG-001"]
severity = { "EC-002" = "error" }
)",
                                            "example.toml");
  ASSERT_TRUE(parsed.has_value()) << parsed.error().text();
  RuleSettings s;
  ASSERT_TRUE(applyConfig(*parsed, s));
  EXPECT_FALSE(s.isEnabled(RuleId::Msg001));
  EXPECT_EQ(s.severityOf(RuleId::Ec002), E);
  EXPECT_EQ(s.readyModeFor(0), 1);
  EXPECT_EQ(s.readyModeFor(1), 0);
  EXPECT_EQ(s.timeoutNs(Timeout::DriveResponse), 20'000'000);
}

}  // namespace
}  // namespace ncservo
