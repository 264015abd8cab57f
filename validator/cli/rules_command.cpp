// `ncservo rules` (docs/rules.md is its markdown): the rule table as text, and one rule in full.
// Not rules.cpp: include_cycles.py takes a header and a source of one name for one module.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "ncservo/rules/rules.hpp"

namespace ncservo::cli {

using namespace report;  // the report layer's names
namespace {

void printRuleText(const RuleDef& rule) {
  fmt::print("{:<8} {:<27} {:<8} {:<6} {}{}\n", rule.code, rule.slug, severityName(rule.severity),
             partyName(rule.party), rule.summary,
             rule.by_default == ByDefault::Off ? " (off by default)" : "");
}

const TimeoutDef& timeoutDef(Timeout timeout) {
  return kTimeouts[static_cast<std::size_t>(timeout)];
}

// "drive_response (20 ms)", or "" for a rule without a timeout.
std::string timeoutText(const RuleDef& rule) {
  if (!rule.timeout) return "";
  const TimeoutDef& t = timeoutDef(*rule.timeout);
  return fmt::format("{} ({} ms)", t.name, t.default_ms);
}

const char* byDefaultName(ByDefault by_default) {
  return by_default == ByDefault::On ? "on" : "off";
}

void printRuleMarkdown(const RuleDef& rule) {
  // An anchor per rule: SARIF's helpUri (report.cpp) links each rule here.
  fmt::print("| <a id=\"{}\"></a>{} | `{}` | {} | {} | {} | {} | {} | {} | {} | {} |\n",
             report::ruleAnchor(rule), rule.code, rule.slug, severityName(rule.severity),
             byDefaultName(rule.by_default), partyName(rule.party), ruleKindName(rule.kind),
             describeReads(rule.reads), timeoutText(rule), rule.clause, rule.summary);
}

// The timeouts with their defaults and the rules that use them.
void printTimeoutsMarkdown() {
  fmt::print(
      "\n| timeout | default (ms) | used by |\n"
      "|---|---|---|\n");
  for (const TimeoutDef& t : kTimeouts) {
    std::vector<std::string> users;
    for (const RuleDef& rule : kRules) {
      if (rule.timeout == t.id) users.emplace_back(rule.code);
    }
    fmt::print("| `{}` | {} | {} |\n", t.name, t.default_ms,
               users.empty() ? std::string("capture segments (a longer pause starts one)")
                             : fmt::format("{}", fmt::join(users, ", ")));
  }
}

// The timeouts, then the limits of the rules that are off by default.
void printRuleSettingsMarkdown() {
  printTimeoutsMarkdown();
  fmt::print(
      "\n| limit | default | range | used by |\n"
      "|---|---|---|---|\n");
  for (const LimitDef& l : kLimits) {
    std::vector<std::string> users;
    for (const RuleDef& rule : kRules) {
      if (rule.limit == l.id) users.emplace_back(rule.code);
    }
    fmt::print("| `{}` | {} | {} to {} ({}) | {} |\n", l.name, l.default_value, l.min, l.max,
               l.unit, fmt::join(users, ", "));
  }
}

// `rules`'s formats: a header, then one line per rule, then an optional footer.
struct RuleListFormat {
  const char* name;
  const char* header;
  void (*rule)(const RuleDef& rule);
  void (*footer)();
};
const RuleListFormat kRuleListFormats[] = {
    {.name = "text", .header = "", .rule = printRuleText, .footer = nullptr},
    {.name = "markdown",
     .header =
         "| ID | slug | severity | by default | party | judged on | reads | timeout (default) "
         "| clause | summary |\n"
         "|---|---|---|---|---|---|---|---|---|---|\n",
     .rule = printRuleMarkdown,
     .footer = printRuleSettingsMarkdown},
};

// `rules --explain ID`: one rule in full, from its row of the rule table.
void explainRule(const RuleDef& rule) {
  fmt::print("{} {}\n", rule.code, rule.slug);
  fmt::print("  fires when:  {}\n", rule.summary);
  fmt::print("  severity:    {} (change it with --severity {}=LEVEL)\n",
             severityName(rule.severity), rule.code);
  if (rule.by_default == ByDefault::Off) {
    fmt::print("  by default:  off (run it with --enable {} or [rules] enable)\n", rule.code);
  }
  if (rule.limit) {
    const LimitDef& l = kLimits[static_cast<std::size_t>(*rule.limit)];
    fmt::print(
        "  limit:       {}, default {} ({}) (--limit {}=VALUE, or {} in the configuration)\n",
        l.name, l.default_value, l.unit, l.name, l.name);
  }
  fmt::print("  party:       {}\n", partyName(rule.party));
  fmt::print("  judged on:   {}\n", ruleKindName(rule.kind));
  if (rule.timeout) {
    const TimeoutDef& t = timeoutDef(*rule.timeout);
    fmt::print("  timeout:     {}, default {} ms (--timeout {}=MS, [timeouts] {})\n", t.name,
               t.default_ms, t.name, t.name);
  }
  fmt::print("  reported:    {}\n",
             rule.timeout_use == TimeoutUse::Around
                 ? "once the timeout has passed after the event, when nothing answered it within "
                   "the timeout before or after it"
             : rule.delayed()              ? "once the condition has held longer than the timeout"
             : rule.reported != nullptr    ? rule.reported
             : rule.kind == RuleKind::Axis ? "on the frame where the condition begins"
                                           : "on the frame of the event");
  fmt::print("  reads:       {}\n", describeReads(rule.reads));
  fmt::print("  clause:      {}\n", rule.clause);
  fmt::print("  filter:      {}\n", ruleFilterName(rule));
  fmt::print("  docs:        docs/rules.md\n");
}

}  // namespace

Handler rulesCommand(CLI::App& command) {
  struct RulesArgs {
    std::string format = kRuleListFormats[0].name;
    std::string explain;
  };
  auto args = std::make_shared<RulesArgs>();
  addFormatOption(command, args->format, namesOf(kRuleListFormats));
  command.add_option("--explain", args->explain,
                     "print one rule in full: what fires it, its timeout and default, what it "
                     "reads (ID in any case)");
  return [args] {
    if (!args->explain.empty()) {
      const Result<const RuleDef*> rule = findRule(args->explain);
      if (!rule) {
        fmt::print(stderr, "ncservo rules: {}\n", rule.error().text());
        return kExitUsage;
      }
      explainRule(**rule);
      return kExitOk;
    }
    const RuleListFormat& list = rowNamed(kRuleListFormats, args->format);
    fmt::print("{}", list.header);
    for (const RuleDef& rule : kRules) list.rule(rule);
    if (list.footer != nullptr) list.footer();
    return kExitOk;
  };
}

}  // namespace ncservo::cli
