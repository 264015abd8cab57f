// `ncservo diff BASE NEW` (docs/baselines.md): two captures or JSON reports compared: findings,
// incidents, timing.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "capture_check.hpp"
#include "commands.hpp"
#include "ncservo/report/report.hpp"

namespace ncservo::cli {

using namespace report;  // the report layer's names
namespace {

struct DiffArgs {
  std::string base, next;
  std::string format = report::diffFormatNames().front();
  std::string output;
  cli::FailOnArgs fail_on;
  CheckArgs check;
};

// One side of a diff: a JSON report of validate (its one capture), or a capture validated as
// validate does. Exit status 3 when it cannot be read, 2 when a report holds several captures.
struct DiffSide {
  int rc = kExitOk;
  report::ReportedCapture capture;
};
DiffSide diffSide(const std::string& path, const CheckSetup& setup,
                  const report::ReportWriter& writer, CaptureThreads threads) {
  if (report::looksLikeJsonReport(path)) {
    Result<report::ReportFile> report = report::loadReportFile(path);
    if (!report) {
      fmt::print(stderr, "ncservo diff: {}\n", report.error().text());
      return {kExitCapture, {}};
    }
    if (report->captures.size() != 1) {
      fmt::print(stderr, "ncservo diff: {}: holds {} captures; diff compares one with one\n", path,
                 report->captures.size());
      return {kExitUsage, {}};
    }
    return {kExitOk, std::move(report->captures.front())};
  }
  report::CaptureReport report;
  const int rc = validateCapture(path, setup, writer, {nullptr, stderr}, report, threads);
  if (rc == kExitCapture) return {rc, {}};
  return {kExitOk, report::reportedCaptureOf(report, writer.judge().verdict(report))};
}

int runDiff(const DiffArgs& o) {
  if (o.base == "-" && o.next == "-") {
    fmt::print(stderr, "ncservo diff: standard input (-) can be read only once\n");
    return kExitUsage;
  }
  const Result<CheckSetup> setup = prepareCheck(o.check);
  if (!setup) {
    fmt::print(stderr, "ncservo diff: {}\n", setup.error().text());
    return kExitUsage;
  }
  VerdictPolicy policy;
  cli::setFailOn(o.fail_on, true, policy);
  const PolicyJudge judge(policy);
  report::ReportOptions options;
  options.enabled = setup->settings.enabled;
  Result<std::FILE*> out = openOutput(o.output, {o.base, o.next});
  if (!out) {
    fmt::print(stderr, "ncservo diff: {}\n", out.error().text());
    return kExitUsage;
  }
  // No report is written: the captures' findings are kept for the comparison.
  auto writer = report::ReportWriter::open({}, options, judge);
  const CaptureThreads threads = cli::captureThreads(o.check.read_thread, 1);
  DiffSide base = diffSide(o.base, *setup, **writer, threads);
  DiffSide next = base.rc == kExitOk ? diffSide(o.next, *setup, **writer, threads) : DiffSide{};
  int rc = base.rc != kExitOk ? base.rc : next.rc;
  if (rc == kExitOk) {
    report::CaptureDiff diff =
        report::diffCaptures(std::move(base.capture), std::move(next.capture));
    diff.base_source = o.base;
    diff.next_source = o.next;
    report::writeDiff(*out, o.format, diff);
    rc = diffFails(diff, policy.fail_on, policy.never, policy.incidents) ? kExitFindings : kExitOk;
  }
  const bool written = std::fflush(*out) == 0;
  if (*out != stdout) std::fclose(*out);
  if (!written) {
    fmt::print(stderr, "ncservo diff: {}: cannot write\n",
               o.output.empty() ? "standard output" : o.output);
    return kExitUsage;
  }
  return rc;
}

}  // namespace

Handler diffCommand(CLI::App& command) {
  auto args = std::make_shared<DiffArgs>();
  command.add_option("BASE", args->base, "the capture or JSON report compared against")->required();
  command.add_option("NEW", args->next, "the capture or JSON report compared")->required();
  addFormatOption(command, args->format, report::diffFormatNames());
  command.add_option("-o,--output", args->output, "write here (default: standard output)");
  cli::addFailOnOption(command, args->fail_on);
  // A capture is validated as `validate` would, with the same options.
  addLayoutOptions(command, args->check.layout);
  cli::addRuleOptions(command, args->check);
  addTimestampsOption(command, args->check.timestamps);
  addWindowOptions(command, args->check.window);
  cli::addReadThreadOption(command, args->check.read_thread);
  return [args] { return runDiff(*args); };
}

}  // namespace ncservo::cli
