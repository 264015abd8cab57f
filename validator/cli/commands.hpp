// What the subcommands share: the format tables' options, the layout files, the rule settings
// and the time window from the command line, the input-as-output check, and each subcommand's
// setup, which main.cpp's table lists (one file per subcommand).
#pragma once

#include <CLI/CLI.hpp>
#include <cstddef>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/capture/capture_stream.hpp"
#include "ncservo/config/config.hpp"
#include "ncservo/layout/decoder.hpp"
#include "ncservo/layout/eni.hpp"
#include "ncservo/pipeline/capture_pipeline.hpp"
#include "ncservo/report/report.hpp"
#include "ncservo/rules/finding.hpp"
#include "ncservo/rules/rules.hpp"
#include "verdict.hpp"

namespace ncservo::cli {

// The check of an option that takes one of `names` (every enumerated option, docs/cli.md): a value
// that is none of them is an error naming the choices and the closest one ("did you mean").
CLI::Validator oneOf(std::vector<std::string> names);

// What runs a subcommand once its options are parsed.
using Handler = std::function<int()>;

// ---- Format tables and the --format option derived from them ----

template <typename Row, std::size_t N>
std::vector<std::string> namesOf(const Row (&rows)[N]) {
  std::vector<std::string> names;
  for (const Row& row : rows) names.emplace_back(row.name);
  return names;
}

// The row `--format` chose; its check admits only the table's names.
template <typename Row, std::size_t N>
const Row& rowNamed(const Row (&rows)[N], const std::string& name) {
  for (const Row& row : rows) {
    if (name == row.name) return row;
  }
  return rows[0];
}

// "a, b or c".
std::string choiceList(const std::vector<std::string>& names);

// --format, one of `names`; its help lists them, then `note`.
void addFormatOption(CLI::App& command, std::string& format, const std::vector<std::string>& names,
                     const std::string& note = "");

// --timestamps (docs/protocol.md §8: a probe's clock or the capturing PC's).
void addTimestampsOption(CLI::App& command, std::string& timestamps);

// --read-thread when not given: one thread (docs/cli.md#two-threads measures why).
inline constexpr const char* kReadThreadDefault = "off";
// --read-thread on|off|auto (docs/cli.md#two-threads): whether a capture is read and walked on a
// thread of its own while another judges it.
void addReadThreadOption(CLI::App& command, std::string& read_thread);
// The threads of each of `captures` captures read at once, each keeping `busy` threads busy
// without the reading thread: auto adds it when the cores hold one more thread per capture.
CaptureThreads captureThreads(const std::string& read_thread, unsigned captures, unsigned busy = 1);

// --fail-on and --fail-on-incident (docs/cli.md#exit-status): the least severity whose findings
// make the exit status 1, or never; the kinds of incident that do; and what they set in the
// report's policy. Without --fail-on-incident, incidents fail a run only against a baseline
// (`against_baseline`: validate --baseline, diff), and never under --fail-on never.
struct FailOnArgs {
  std::string findings = "error";
  std::string incidents;  // empty: not given
};
void addFailOnOption(CLI::App& command, FailOnArgs& fail_on);
void setFailOn(const FailOnArgs& fail_on, bool against_baseline, VerdictPolicy& policy);

// The layout files of every command that reads a capture (docs/protocol.md §9.1, §9.2).
struct LayoutArgs {
  std::string config_path;
  std::string eni_path;
  bool no_default_layout = false;
};
struct LayoutFiles {
  std::optional<Config> config;
  std::optional<EniLayout> eni;
};
// --config, --no-default-layout and --eni: one declaration, so every command's help says the same.
void addLayoutOptions(CLI::App& command, LayoutArgs& layout);
Result<LayoutFiles> loadLayoutFiles(const LayoutArgs& args);
DecoderOptions decoderOptions(const LayoutFiles& files, const LayoutArgs& args);

// The rule settings of the command line (docs/cli.md, `validate`).
struct RuleArgs {
  std::vector<std::string> disable;
  std::vector<std::string> enable;
  std::vector<std::string> severities;
  std::vector<std::string> limits;
  std::vector<std::string> timeouts;
  std::optional<int> servo_ready_mode;
};
// --disable, --enable, --severity, --timeout, --limit and --servo-ready-mode.
void addRuleOptions(CLI::App& command, RuleArgs& rules);
// The settings from the rules' defaults, the config file, then the command line.
Status buildSettings(const RuleArgs& o, const std::optional<Config>& config,
                     RuleSettings& settings);

// --from/--to (docs/cli.md), seconds since the capture's first frame.
struct WindowArgs {
  std::optional<std::string> from, to;  // seconds or ISO 8601 times (docs/cli.md#time-window)
  bool local_time = false;              // --local-time
  TimeZone zone() const { return local_time ? TimeZone::Local : TimeZone::Utc; }
};
void addWindowOptions(CLI::App& command, WindowArgs& window);

// What a snap length cut, on one line (never one per frame).
void warnIfTruncated(const std::string& capture, const Truncation& truncation,
                     std::FILE* messages = stderr);

// docs/cli.md#exit-status: an output path that is one of the inputs, however named, is a usage
// error, checked before anything is opened for writing.
Status refuseInputAsOutput(const std::string& option, const std::string& output,
                           const std::vector<std::string>& captures);

// `-o FILE`, or standard output for none or "-".
Result<std::FILE*> openOutput(const std::string& output, const std::vector<std::string>& captures);

// A finding as a packet comment (annotate, the flight recorder): "SE-001 illegal-enable-edge
// axis X: what was seen", and where the condition began when that is an earlier frame.
std::string findingComment(const Finding& finding, const std::vector<AxisInfo>& axes);
// Whether a packet comment is one findingComment wrote ("RULE-ID slug ..."): annotating an
// annotated capture replaces those and keeps everyone else's (docs/field.md).
bool isFindingComment(std::string_view comment);

// The subcommands' setups: each declares its options and returns what runs it.
Handler decodeCommand(CLI::App& command);
Handler validateCommand(CLI::App& command);
Handler diffCommand(CLI::App& command);
Handler rulesCommand(CLI::App& command);
Handler fieldsCommand(CLI::App& command);
Handler simulateCommand(CLI::App& command);
Handler annotateCommand(CLI::App& command);
Handler monitorCommand(CLI::App& command);
Handler mergeCommand(CLI::App& command);

}  // namespace ncservo::cli
