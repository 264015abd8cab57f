// `ncservo validate` (docs/cli.md): captures checked against the rules, one after another or
// --jobs at once, each report written in argument order.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "capture_check.hpp"
#include "commands.hpp"
#include "ncservo/base/ordered_jobs.hpp"
#include "ncservo/report/report.hpp"

namespace ncservo::cli {

using namespace report;  // the report layer's names
namespace {

struct ValidateArgs : CheckArgs {
  std::vector<std::string> captures;
  std::string format = report::reportFormatNames().front();
  std::string output;
  cli::FailOnArgs fail_on;
  bool allow_empty = false;
  bool verbose = false;
  std::optional<unsigned> jobs;      // default: the cores
  std::vector<std::string> reports;  // FORMAT:FILE
  std::string baseline;              // a JSON report (docs/baselines.md)
  std::vector<std::string> axes;     // --axis
  std::string only;                  // --only findings|incidents
};

// A capture validated apart (CaptureOutput without `live`) given to the writer as if it had
// been written as it came: its messages, its findings one by one, its end.
void presentCapture(report::ReportWriter& writer, const std::string& messages,
                    report::CaptureReport& report) {
  std::fputs(messages.c_str(), stderr);
  writer.beginCapture(report);
  for (std::size_t i = 0; i < report.findings.size(); ++i) {
    writer.finding(report, report.findings[i],
                   report.baseline ? report.baseline_states[i] : report::BaselineState::None);
  }
  writer.endCapture(report);
  if (!writer.keepsFindings()) {
    std::vector<Finding>().swap(report.findings);
    std::vector<report::BaselineState>().swap(report.baseline_states);
  }
}

// docs/cli.md: with several captures the status is the most serious, in the order 2, 3, 1, 4, 0.
int combine(int a, int b) {
  return moreSerious(a, b);
}

// Whether two paths name one file, however spelt (links, "./"), whether or not it exists yet.
bool sameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (std::filesystem::equivalent(a, b, ec)) return true;
  const auto canonical_a = std::filesystem::weakly_canonical(a, ec);
  if (ec) return false;
  const auto canonical_b = std::filesystem::weakly_canonical(b, ec);
  return !ec && canonical_a == canonical_b;
}

// The reports of a run: --format to --output (standard output by default), then each
// --report FORMAT:FILE. docs/cli.md: a report file that is one of the inputs, however named,
// is a usage error, and so are two reports to one file; checked before anything is written.
Result<std::vector<report::ReportTarget>> reportTargets(const ValidateArgs& o) {
  std::vector<report::ReportTarget> targets{{report::findReportFormat(o.format), o.output}};
  std::vector<std::string> options{"--output"};
  for (const std::string& spec : o.reports) {
    const auto colon = spec.find(':');
    const report::ReportFormat* format =
        colon == std::string::npos ? nullptr : report::findReportFormat(spec.substr(0, colon));
    if (format == nullptr || colon + 1 == spec.size()) {
      return fail(fmt::format("--report {}: expected FORMAT:FILE, FORMAT one of {}", spec,
                              choiceList(report::reportFormatNames())));
    }
    const std::string path = spec.substr(colon + 1);
    if (path == "-") {
      return fail(
          fmt::format("--report {}: standard output has the --format report; give a file", spec));
    }
    targets.push_back({format, path});
    options.push_back("--report " + spec.substr(0, colon) + ":");
  }
  for (std::size_t t = 0; t < targets.size(); ++t) {
    const std::string& path = targets[t].path;
    if (path.empty() || path == "-") continue;
    if (Status refused = refuseInputAsOutput(options[t], path, o.captures); !refused)
      return fail(refused.error());
    for (std::size_t u = 0; u < t; ++u) {
      const std::string& other = targets[u].path;
      if (!other.empty() && other != "-" && sameFile(path, other)) {
        return fail(fmt::format("{} {} and {} {} are one file: give each report its own",
                                options[u], other, options[t], path));
      }
    }
  }
  return targets;
}

// docs/baselines.md: a baseline that cannot be read is a usage error, as a bad --config is.
Result<std::optional<report::ReportFile>> loadBaseline(const ValidateArgs& o) {
  if (o.baseline.empty()) return std::nullopt;
  Result<report::ReportFile> loaded = report::loadReportFile(o.baseline);
  if (!loaded) return fail(loaded.error());
  return std::move(*loaded);
}

// The reports to fill, one per capture, each with its capture's part of the baseline.
std::vector<report::CaptureReport> emptyReports(const ValidateArgs& o,
                                                const std::optional<report::ReportFile>& baseline) {
  std::vector<report::CaptureReport> reports(o.captures.size());
  for (report::CaptureReport& report : reports) {
    report.zone = o.window.zone();
    report.scope.axes = o.axes;
    report.scope.findings = o.only != "incidents";
    report.scope.incidents = o.only != "findings";
  }
  if (baseline) {
    for (std::size_t i = 0; i < o.captures.size(); ++i) {
      const report::ReportedCapture* matched =
          report::baselineCaptureFor(*baseline, o.captures[i], o.captures.size());
      if (matched == nullptr) {
        fmt::print(stderr,
                   "ncservo: {}: no capture of this file name in the baseline {}: each of its "
                   "findings is new\n",
                   o.captures[i], o.baseline);
      }
      reports[i].baseline.emplace(matched);
      reports[i].baseline_path = o.baseline;
    }
  }
  return reports;
}

// Each capture validated in parallel, `jobs` at once, its messages kept with its report; each is
// given to the writer in argument order as soon as the ones before it are.
void validateInParallel(const ValidateArgs& o, const CheckSetup& setup,
                        report::ReportWriter& writer, unsigned jobs, CaptureThreads threads,
                        std::vector<report::CaptureReport>& reports, std::vector<int>& statuses) {
  const std::atomic<bool>& interrupted = report::ReportWriter::interrupted();
  struct Validated {
    int rc;
    std::string messages;
  };
  const std::function<Validated(std::size_t)> validate = [&](std::size_t i) {
    if (interrupted) return Validated{kExitInterrupted, {}};
    char* buffer = nullptr;
    std::size_t size = 0;
    std::FILE* messages = open_memstream(&buffer, &size);
    const int status =
        validateCapture(o.captures[i], setup, writer, {nullptr, messages}, reports[i], threads);
    std::fclose(messages);
    Validated validated{status, std::string(buffer, size)};
    std::free(buffer);
    return validated;
  };
  const std::function<void(std::size_t, Validated&)> present = [&](std::size_t i,
                                                                   Validated& validated) {
    statuses[i] = validated.rc;
    if (validated.rc == kExitInterrupted) {
      std::fputs(validated.messages.c_str(), stderr);
      return;
    }
    presentCapture(writer, validated.messages, reports[i]);
  };
  runInOrder(o.captures.size(), jobs, validate, present);
}

// docs/cli.md#interrupted: each capture's status; kExitInterrupted for one Ctrl-C stopped or kept
// from starting (`reports[i].frames` then says how far it got).
std::vector<int> validateCaptures(const ValidateArgs& o, const CheckSetup& setup,
                                  report::ReportWriter& writer,
                                  std::vector<report::CaptureReport>& reports) {
  std::vector<int> statuses(o.captures.size(), kExitInterrupted);
  writer.stopOnInterrupt();
  const std::atomic<bool>& interrupted = report::ReportWriter::interrupted();
  const unsigned jobs = o.jobs.value_or(std::max(1u, std::thread::hardware_concurrency()));
  const bool one_at_a_time = jobs <= 1 || o.captures.size() <= 1;
  // docs/cli.md#two-threads: the reading threads and --jobs share the cores.
  const CaptureThreads threads = cli::captureThreads(
      o.read_thread,
      one_at_a_time ? 1u : static_cast<unsigned>(std::min<std::size_t>(jobs, o.captures.size())));
  if (one_at_a_time) {
    for (std::size_t i = 0; i < o.captures.size() && !interrupted; ++i) {
      statuses[i] =
          validateCapture(o.captures[i], setup, writer, {&writer, stderr}, reports[i], threads);
    }
  } else {
    validateInParallel(o, setup, writer, jobs, threads, reports, statuses);
  }
  return statuses;
}

// Only finished captures are reported; where Ctrl-C stopped the others is said on stderr.
// Returns the exit status of them all.
int finishReports(const ValidateArgs& o, const std::vector<int>& statuses,
                  std::vector<report::CaptureReport>& reports, report::ReportWriter& writer) {
  int rc = kExitOk;
  std::vector<report::CaptureReport> finished;
  std::vector<std::string> unstarted;
  for (std::size_t i = 0; i < o.captures.size(); ++i) {
    if (statuses[i] != kExitInterrupted) {
      rc = combine(rc, statuses[i]);
      finished.push_back(std::move(reports[i]));
    } else if (reports[i].path.empty()) {
      unstarted.push_back(o.captures[i]);
    } else {
      fmt::print(stderr, "ncservo: interrupted at {}, frame {}\n",
                 o.captures[i] == "-" ? std::string("standard input") : o.captures[i],
                 reports[i].frames);
      rc = kExitInterrupted;
    }
  }
  // Before the reports were written, as the text says.
  if (report::ReportWriter::interrupted()) rc = kExitInterrupted;
  if (!unstarted.empty()) {
    fmt::print(stderr, "ncservo: interrupted before {}\n", fmt::join(unstarted, ", "));
  }
  if (Status written = writer.finish(finished); !written) {
    fmt::print(stderr, "ncservo: {}\n", written.error().text());
    return kExitUsage;
  }
  return rc;
}

int runValidate(const ValidateArgs& o) {
  if (std::count(o.captures.begin(), o.captures.end(), "-") > 1) {
    fmt::print(stderr, "ncservo: standard input (-) can be read only once\n");
    return kExitUsage;
  }
  const Result<CheckSetup> setup = prepareCheck(o);
  if (!setup) {
    fmt::print(stderr, "ncservo: {}\n", setup.error().text());
    return kExitUsage;
  }
  const Result<std::optional<report::ReportFile>> baseline = loadBaseline(o);
  if (!baseline) {
    fmt::print(stderr, "ncservo: --baseline {}\n", baseline.error().text());
    return kExitUsage;
  }
  const Result<std::vector<report::ReportTarget>> targets = reportTargets(o);
  if (!targets) {
    fmt::print(stderr, "ncservo: {}\n", targets.error().text());
    return kExitUsage;
  }
  VerdictPolicy policy;
  cli::setFailOn(o.fail_on, !o.baseline.empty(), policy);
  policy.allow_empty = o.allow_empty;
  const PolicyJudge judge(policy);
  report::ReportOptions options;
  options.verbose = o.verbose;
  options.enabled = setup->settings.enabled;
  auto writer = report::ReportWriter::open(*targets, options, judge);
  if (!writer) {
    fmt::print(stderr, "ncservo: {}\n", writer.error().text());
    return kExitUsage;
  }
  std::vector<report::CaptureReport> reports = emptyReports(o, *baseline);
  const std::vector<int> statuses = validateCaptures(o, *setup, **writer, reports);
  return finishReports(o, statuses, reports, **writer);
}

}  // namespace

Handler validateCommand(CLI::App& command) {
  auto args = std::make_shared<ValidateArgs>();
  command.add_option("CAPTURE", args->captures, "pcap or pcapng captures, - for standard input")
      ->required();
  addLayoutOptions(command, args->layout);
  addFormatOption(command, args->format, report::reportFormatNames());
  command.add_option("-o,--output", args->output,
                     "write the report here (default: standard output)");
  command
      .add_option("--report", args->reports,
                  "FORMAT:FILE: also write that report to that file (repeatable)")
      ->allow_extra_args(false);
  command.add_flag("-v,--verbose", args->verbose,
                   "text: every finding, not one line per rule and axis");
  cli::addFailOnOption(command, args->fail_on);
  command.add_option("--baseline", args->baseline,
                     "REPORT.json: a JSON report of an earlier run; each finding is new or "
                     "unchanged against it, and --fail-on counts the new ones (docs/baselines.md)");
  cli::addRuleOptions(command, *args);
  addTimestampsOption(command, args->timestamps);
  addWindowOptions(command, args->window);
  command.add_option("--axis", args->axes,
                     "NAME: report only this axis's findings and incidents, and the bus's "
                     "(repeatable; docs/cli.md#scope)");
  command.add_option("--only", args->only, "report only findings, or only incidents")
      ->check(CLI::IsMember({"findings", "incidents"}));
  command.add_flag("--allow-empty", args->allow_empty,
                   "exit 0, not 4, where no servo (or not every configured axis) was decoded");
  command
      .add_option("-j,--jobs", args->jobs,
                  "validate this many captures at once (default: the cores); the output is "
                  "in argument order, as with 1")
      ->check(CLI::Range(1u, 1024u));
  cli::addReadThreadOption(command, args->read_thread);
  return [args] { return runValidate(*args); };
}

}  // namespace ncservo::cli
