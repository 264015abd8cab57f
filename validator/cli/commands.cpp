#include "commands.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string_view>
#include <thread>
#include <vector>

#include "ncservo/base/number.hpp"
#include "ncservo/base/text.hpp"

namespace ncservo::cli {

using namespace report;  // the report layer's names

CLI::Validator oneOf(std::vector<std::string> names) {
  const std::string choices = fmt::format("{{{}}}", fmt::join(names, ","));
  return CLI::Validator(
      [names = std::move(names), choices](std::string& value) -> std::string {
        if (std::find(names.begin(), names.end(), value) != names.end()) return {};
        return fmt::format("{} is not one of {}{}", value, choices, didYouMean(value, names));
      },
      choices);
}

std::string choiceList(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) {
    text += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  }
  return text;
}

void addFormatOption(CLI::App& command, std::string& format, const std::vector<std::string>& names,
                     const std::string& note) {
  command.add_option("--format", format, choiceList(names) + note)->check(oneOf(names));
}

void addTimestampsOption(CLI::App& command, std::string& timestamps) {
  command
      .add_option("--timestamps", timestamps,
                  "capture, probe or auto (auto: an ESL probe's when the first EtherCAT frame "
                  "has one)")
      ->check(oneOf({"capture", "probe", "auto"}));
}

namespace {

// The choices of --read-thread: how many threads each names (auto: none, the cores decide).
struct ReadThreadChoice {
  const char* name;
  std::optional<CaptureThreads> threads;
};
constexpr ReadThreadChoice kReadThreadChoices[] = {
    {"off", CaptureThreads::One}, {"on", CaptureThreads::Two}, {"auto", std::nullopt}};

}  // namespace

void addReadThreadOption(CLI::App& command, std::string& read_thread) {
  std::vector<std::string> names;
  for (const ReadThreadChoice& choice : kReadThreadChoices) names.emplace_back(choice.name);
  command
      .add_option("--read-thread", read_thread,
                  fmt::format("{} (default {}): read and walk the frames on a thread of their own "
                              "while another judges them (auto: when the cores hold it; "
                              "docs/cli.md#two-threads)",
                              fmt::join(names, ", "), kReadThreadDefault))
      ->check(oneOf(names));
}

CaptureThreads captureThreads(const std::string& read_thread, unsigned captures, unsigned busy) {
  for (const ReadThreadChoice& choice : kReadThreadChoices) {
    if (read_thread == choice.name && choice.threads) return *choice.threads;
  }
  const unsigned cores = std::thread::hardware_concurrency();  // 0: unknown, taken as one
  return captures * (busy + 1) <= cores ? CaptureThreads::Two : CaptureThreads::One;
}

void addFailOnOption(CLI::App& command, FailOnArgs& fail_on) {
  command
      .add_option("--fail-on", fail_on.findings,
                  "exit 1 on findings at or above: error, warning, info, never")
      ->check(oneOf({"error", "warning", "info", "never"}));
  command
      .add_option("--fail-on-incident", fail_on.incidents,
                  "exit 1 on incidents of these kinds: drive-fault, bus-outage, esm (joined by "
                  "commas), any or never (default: any new one against a baseline, never "
                  "without one; docs/cli.md#exit-status)")
      ->check(CLI::Validator(
          [](const std::string& text) {
            const Result<IncidentGate> gate = parseIncidentGate(text);
            return gate ? std::string() : gate.error().text();
          },
          "KINDS"));
}

void setFailOn(const FailOnArgs& fail_on, bool against_baseline, VerdictPolicy& policy) {
  policy.never = fail_on.findings == "never";
  policy.fail_on = policy.never ? Severity::Error : *severityFromName(fail_on.findings);
  std::string incidents = fail_on.incidents;
  if (incidents.empty()) incidents = against_baseline && !policy.never ? "any" : "never";
  policy.incidents = *parseIncidentGate(incidents);
}

void addLayoutOptions(CLI::App& command, LayoutArgs& layout) {
  command.add_option("--config", layout.config_path, "TOML configuration file");
  command.add_flag("--no-default-layout", layout.no_default_layout,
                   "never infer the layout from the cyclic traffic (docs/layout.md)");
  command.add_option("--eni", layout.eni_path,
                     "ENI file (EtherCATConfig.xml) giving the layout when no --config does");
}

Result<LayoutFiles> loadLayoutFiles(const LayoutArgs& args) {
  LayoutFiles files;
  if (!args.config_path.empty()) {
    Result<Config> loaded = loadConfig(args.config_path);
    if (!loaded) return fail(loaded.error().text());
    files.config = std::move(*loaded);
  }
  if (!args.eni_path.empty()) {
    Result<EniLayout> eni = loadEni(args.eni_path);
    if (!eni) return fail(eni.error().text());
    if (eni->axes.empty()) {
      return fail(fmt::format(
          "{}: no servo of this protocol (10-byte outputs, 40-byte inputs) among its {} slaves",
          args.eni_path, eni->slaves));
    }
    files.eni = std::move(*eni);
  }
  return files;
}

DecoderOptions decoderOptions(const LayoutFiles& files, const LayoutArgs& args) {
  DecoderOptions options =
      layoutOptions(files.config ? &*files.config : nullptr, files.eni ? &files.eni->axes : nullptr,
                    !args.no_default_layout);
  if (files.eni) options.mailbox_areas = files.eni->mailboxes;
  return options;
}

void addRuleOptions(CLI::App& command, RuleArgs& rules) {
  command.add_option("--disable", rules.disable, "rule IDs to skip, comma-separated (repeatable)")
      ->delimiter(',')
      ->allow_extra_args(false);
  command
      .add_option("--enable", rules.enable,
                  "rule IDs to run that are off by default, comma-separated (repeatable)")
      ->delimiter(',')
      ->allow_extra_args(false);
  command
      .add_option("--severity", rules.severities, "ID=LEVEL: change a rule's severity (repeatable)")
      ->delimiter(',')
      ->allow_extra_args(false);
  command
      .add_option("--timeout", rules.timeouts,
                  "NAME=MS: change a timeout (docs/rules.md; repeatable)")
      ->delimiter(',')
      ->allow_extra_args(false);
  command
      .add_option("--limit", rules.limits,
                  "NAME=VALUE: change a rule's limit, e.g. cycle_jitter_percent=20 (docs/rules.md; "
                  "repeatable)")
      ->delimiter(',')
      ->allow_extra_args(false);
  command
      .add_option("--servo-ready-mode", rules.servo_ready_mode,
                  "Servo_Ready_Mode of the drives (0 or 1)")
      ->check(CLI::Range(0, 1));
}

Status buildSettings(const RuleArgs& o, const std::optional<Config>& config,
                     RuleSettings& settings) {
  // An error of an option names the option.
  auto option = [](const char* name, const Status& status) {
    return fail(fmt::format("{}: {}", name, status.error().message));
  };
  if (config) {
    if (Status s = applyConfig(*config, settings); !s) return s;
  }
  for (const std::string& id : o.disable) {
    if (Status s = settings.disable(id); !s) return option("--disable", s);
  }
  for (const std::string& pair : o.severities) {
    const auto eq = pair.find('=');
    if (eq == std::string::npos) return fail("--severity " + pair + ": expected ID=LEVEL");
    if (Status s = settings.setSeverity(pair.substr(0, eq), pair.substr(eq + 1)); !s)
      return option("--severity", s);
  }
  for (const std::string& id : o.enable) {
    if (Status s = settings.enable(id); !s) return option("--enable", s);
  }
  // NAME=N with N a whole number, or -1.
  auto number = [](const std::string& pair, std::size_t eq) {
    return parseNumber<std::int64_t>(std::string_view(pair).substr(eq + 1)).value_or(-1);
  };
  for (const std::string& pair : o.timeouts) {
    const auto eq = pair.find('=');
    if (eq == std::string::npos) return fail("--timeout " + pair + ": expected NAME=MS");
    const std::int64_t ms = number(pair, eq);
    if (ms < 0) return fail("--timeout " + pair + ": expected a number of milliseconds");
    if (Status s = settings.setTimeout(pair.substr(0, eq), ms); !s) return option("--timeout", s);
  }
  for (const std::string& pair : o.limits) {
    const auto eq = pair.find('=');
    if (eq == std::string::npos) return fail("--limit " + pair + ": expected NAME=VALUE");
    const std::int64_t value = number(pair, eq);
    if (value < 0) return fail("--limit " + pair + ": expected a whole number");
    if (Status s = settings.setLimit(pair.substr(0, eq), value); !s) return option("--limit", s);
  }
  if (o.servo_ready_mode) settings.servo_ready_mode = o.servo_ready_mode;
  return {};
}

void addWindowOptions(CLI::App& command, WindowArgs& window) {
  command.add_option("--from", window.from,
                     "only frames at or after TIME: seconds since the capture's first frame, or "
                     "an ISO 8601 time (2024-05-01T10:41:00Z)");
  command.add_option("--to", window.to,
                     "only frames at or before TIME: seconds since the capture's first frame, or "
                     "an ISO 8601 time");
  command.add_flag("--local-time", window.local_time,
                   "times of day in this machine's local time (TZ), not UTC: the report's, and "
                   "an ISO --from/--to without an offset");
}

void warnIfTruncated(const std::string& capture, const Truncation& truncation,
                     std::FILE* messages) {
  if (truncation.any()) {
    fmt::print(messages, "ncservo: {}: {}\n", capture, describeTruncation(truncation));
  }
}

Status refuseInputAsOutput(const std::string& option, const std::string& output,
                           const std::vector<std::string>& captures) {
  for (const std::string& capture : captures) {
    std::error_code ec;
    if (capture != "-" && std::filesystem::equivalent(output, capture, ec)) {
      return fail(fmt::format("{} {} is the capture {}: refusing to write over an input", option,
                              output, capture));
    }
  }
  return {};
}

Result<std::FILE*> openOutput(const std::string& output, const std::vector<std::string>& captures) {
  if (output.empty() || output == "-") return stdout;
  if (Status refused = refuseInputAsOutput("--output", output, captures); !refused)
    return fail(refused.error());
  std::FILE* out = std::fopen(output.c_str(), "w");
  if (out == nullptr)
    return fail(fmt::format("{}: cannot write: {}", output, std::strerror(errno)));
  return out;
}

// "SE-001 illegal-enable-edge axis X: what was seen", and where the condition began when that
// is an earlier frame.
bool isFindingComment(std::string_view comment) {
  const std::size_t space = comment.find(' ');
  if (space == std::string_view::npos) return false;
  const RuleDef* rule = ruleByCode(comment.substr(0, space));
  if (rule == nullptr || comment.substr(0, space) != rule->code) return false;
  const std::string_view rest = comment.substr(space + 1);
  const std::string_view slug = rule->slug;
  return rest.substr(0, slug.size()) == slug && rest.size() > slug.size() &&
         rest[slug.size()] == ' ';
}

std::string findingComment(const Finding& finding, const std::vector<AxisInfo>& axes) {
  std::string where = "bus";
  if (finding.axis) {
    where = fmt::format("axis axis{}", *finding.axis);
    for (const AxisInfo& axis : axes) {
      if (axis.index == *finding.axis) where = "axis " + axis.name;
    }
  }
  const RuleDef& rule = ruleDef(finding.rule);
  return fmt::format("{} {} {}: {}{}", rule.code, rule.slug, where, finding.message,
                     finding.since.frame != finding.at.frame && finding.since.frame != 0
                         ? fmt::format(" (since frame {})", finding.since.frame)
                         : "");
}

}  // namespace ncservo::cli
