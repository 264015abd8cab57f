// What fails a run: the exit statuses of every command, and the policy of --fail-on,
// --fail-on-incident and --allow-empty that turns a capture's report into its verdict and its
// exit status (docs/cli.md#verdicts, docs/cli.md#exit-status). The reports show these decisions
// (report::Judge); they are taken here.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/report/baseline.hpp"
#include "ncservo/report/report.hpp"

namespace ncservo::cli {

// The exit statuses of every command (docs/cli.md#exit-status).
enum ExitCode {
  kExitOk = 0,
  kExitFindings = 1,
  kExitUsage = 2,
  kExitCapture = 3,
  kExitNoServo = 4,
  kExitInterrupted = 130,  // 128 + SIGINT, as a shell reports a run Ctrl-C ended
};

// The kinds of incident that fail a run (--fail-on-incident), by IncidentKind.
struct IncidentGate {
  std::array<bool, 3> kinds{true, true, true};
  bool any() const { return kinds[0] || kinds[1] || kinds[2]; }
  bool gates(std::string_view kind) const;
};
// "any", "never", or kinds joined by commas ("drive-fault,esm"); what the option was given.
std::string incidentGateText(const IncidentGate& gate);
// Parses the option's value: any, never, or a comma-separated list of kinds; fails naming the
// word it does not know.
Result<IncidentGate> parseIncidentGate(std::string_view text);

// When a capture fails the run: findings at or above `fail_on` (unless `never`; against a
// baseline only the new ones count), incidents of a kind `incidents` gates (against a baseline
// only the new ones), and a capture where not every axis was checked unless `allow_empty`.
struct VerdictPolicy {
  Severity fail_on = Severity::Error;
  bool never = false;
  IncidentGate incidents;
  bool allow_empty = false;
};

// Whether incident `index` of the capture fails the run under `gate`, and how many do.
bool incidentGated(const report::CaptureReport& report, std::size_t index,
                   const IncidentGate& gate);
std::size_t gatedIncidents(const report::CaptureReport& report, const IncidentGate& gate);

// A capture's verdict and its exit status (3, 1, 4 or 0), both from the findings counted: the
// one place that decides them.
struct CaptureVerdict {
  report::Verdict verdict;
  int exit_status;
};
CaptureVerdict judgeCapture(const VerdictPolicy& policy, const report::CaptureReport& report);
// With several captures the status is the most serious, in the order 2, 3, 1, 4, 0 (130, an
// interrupted run, before them all).
int moreSerious(int a, int b);
// Why a run's exit status is what it is: "--fail-on never", "findings at or above --fail-on
// warning", …
std::string exitReason(const VerdictPolicy& policy,
                       const std::vector<report::CaptureReport>& reports, int exit_status);

// Whether NEW has a finding at or above `fail_on` that BASE does not (never: false), or an
// incident of a kind `incidents` gates (`ncservo diff`).
bool diffFails(const report::CaptureDiff& diff, Severity fail_on, bool never,
               const IncidentGate& incidents);

// The policy as the reports ask for its decisions.
class PolicyJudge final : public report::Judge {
 public:
  explicit PolicyJudge(const VerdictPolicy& policy) : policy_(policy) {}
  const VerdictPolicy& policy() const { return policy_; }
  report::Verdict verdict(const report::CaptureReport& report) const override;
  int exitStatus(const report::CaptureReport& report) const override;
  bool failsUnchecked(const report::CaptureReport& report) const override;
  bool failsFinding(Severity severity) const override;
  bool failsIncident(const report::CaptureReport& report, std::size_t index) const override;
  // The most serious capture's status, or 130 after a Ctrl-C (report::ReportWriter).
  report::RunStatus runStatus(const std::vector<report::CaptureReport>& reports) const override;

 private:
  VerdictPolicy policy_;
};

}  // namespace ncservo::cli
