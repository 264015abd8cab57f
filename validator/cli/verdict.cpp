#include "verdict.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <iterator>

#include "ncservo/incidents/incident.hpp"

namespace ncservo::cli {

using report::BaselineState;
using report::CaptureDiff;
using report::CaptureReport;
using report::ReportedFinding;
using report::ReportedIncident;
using report::Verdict;

bool IncidentGate::gates(std::string_view kind) const {
  for (std::size_t k = 0; k < kinds.size(); ++k) {
    if (kinds[k] && kind == incidentKindName(static_cast<IncidentKind>(k))) return true;
  }
  return false;
}

std::string incidentGateText(const IncidentGate& gate) {
  if (!gate.any()) return "never";
  if (gate.kinds[0] && gate.kinds[1] && gate.kinds[2]) return "any";
  std::vector<std::string> kinds;
  for (std::size_t k = 0; k < gate.kinds.size(); ++k) {
    if (gate.kinds[k]) kinds.emplace_back(incidentKindName(static_cast<IncidentKind>(k)));
  }
  return fmt::format("{}", fmt::join(kinds, ","));
}

Result<IncidentGate> parseIncidentGate(std::string_view text) {
  if (text == "any") return IncidentGate{};
  IncidentGate gate{{false, false, false}};
  if (text == "never") return gate;
  for (std::size_t comma = 0; comma != std::string_view::npos;) {
    comma = text.find(',');
    const std::string_view word = text.substr(0, comma);
    bool known = false;
    for (std::size_t k = 0; k < gate.kinds.size(); ++k) {
      if (word == incidentKindName(static_cast<IncidentKind>(k))) known = gate.kinds[k] = true;
    }
    if (!known) {
      return fail(fmt::format(
          "'{}' is no kind of incident (drive-fault, bus-outage, esm; or any, never)", word));
    }
    if (comma != std::string_view::npos) text.remove_prefix(comma + 1);
  }
  return gate;
}

bool incidentGated(const CaptureReport& r, std::size_t index, const IncidentGate& gate) {
  const bool new_or_unmatched =
      index >= r.incident_states.size() || r.incident_states[index] != BaselineState::Unchanged;
  return new_or_unmatched && gate.kinds[static_cast<std::size_t>(r.incidents[index].kind)];
}

std::size_t gatedIncidents(const CaptureReport& r, const IncidentGate& gate) {
  std::size_t gated = 0;
  for (std::size_t i = 0; i < r.incidents.size(); ++i) gated += incidentGated(r, i, gate) ? 1 : 0;
  return gated;
}

CaptureVerdict judgeCapture(const VerdictPolicy& policy, const CaptureReport& r) {
  // The findings the verdict is about: all of them, or the new ones against a baseline
  // (docs/baselines.md).
  const auto reaches = [&](Severity level) { return r.reaches(level); };
  // What --fail-on and --fail-on-incident fail.
  const bool gate =
      (!policy.never && reaches(policy.fail_on)) || gatedIncidents(r, policy.incidents) > 0;
  const bool checked = r.coverage.complete();
  if (r.error) return {Verdict::Unreadable, kExitCapture};
  const int status = gate                              ? kExitFindings
                     : !checked && !policy.allow_empty ? kExitNoServo
                                                       : kExitOk;
  // The words describe the capture (docs/cli.md#verdicts): an error is a FAIL whatever --fail-on
  // says, and so is a finding that fails the gate when --fail-on is stricter.
  if (gate || reaches(Severity::Error)) return {Verdict::Fail, status};
  if (!checked) return {Verdict::NoServo, status};
  if (reaches(Severity::Warning)) return {Verdict::Warn, status};
  return {Verdict::Pass, status};
}

int moreSerious(int a, int b) {
  constexpr int kOrder[] = {kExitInterrupted, kExitUsage,   kExitCapture,
                            kExitFindings,    kExitNoServo, kExitOk};
  auto rank = [&](int rc) { return std::find(std::begin(kOrder), std::end(kOrder), rc) - kOrder; };
  return rank(a) <= rank(b) ? a : b;
}

namespace {

// What made the exit status 1: findings at or above --fail-on, incidents --fail-on-incident
// gates, or both.
std::string gateReason(const VerdictPolicy& policy, const std::vector<CaptureReport>& reports) {
  bool findings = false;
  std::size_t incidents = 0;
  for (const CaptureReport& r : reports) {
    findings = findings || (!policy.never && r.reaches(policy.fail_on));
    incidents += gatedIncidents(r, policy.incidents);
  }
  std::vector<std::string> why;
  if (findings) {
    why.push_back(fmt::format("findings at or above --fail-on {}", severityName(policy.fail_on)));
  }
  if (incidents > 0) {
    why.push_back(fmt::format("{} incident{} under --fail-on-incident {}", incidents,
                              incidents == 1 ? "" : "s", incidentGateText(policy.incidents)));
  }
  return fmt::format("{}", fmt::join(why, ", "));
}

}  // namespace

std::string exitReason(const VerdictPolicy& policy, const std::vector<CaptureReport>& reports,
                       int exit_status) {
  const std::string fail_on = policy.never ? "never" : severityName(policy.fail_on);
  switch (exit_status) {
    case kExitCapture:
      return "a capture could not be read to its end";
    case kExitFindings:
      return gateReason(policy, reports);
    case kExitNoServo:
      return "no servo checked";
    case kExitOk:
      break;
    default:
      return "";
  }
  bool findings = false;
  std::size_t ungated = 0;    // incidents of kinds --fail-on-incident leaves out
  std::size_t unchanged = 0;  // incidents the baseline had
  bool unchecked = false;
  for (const CaptureReport& r : reports) {
    findings = findings || r.reaches(Severity::Info);
    for (std::size_t i = 0; i < r.incidents.size(); ++i) {
      const bool same =
          i < r.incident_states.size() && r.incident_states[i] == BaselineState::Unchanged;
      (same ? unchanged : ungated) += 1;
    }
    unchecked = unchecked || (!r.unopened() && !r.coverage.complete());
  }
  std::vector<std::string> why;
  if (findings) {
    why.push_back(policy.never ? std::string("--fail-on never")
                               : fmt::format("nothing at or above --fail-on {}", fail_on));
  }
  // --fail-on never alone gates no incident either: said once.
  if (ungated > 0 && !(policy.never && !policy.incidents.any())) {
    why.push_back(fmt::format("{} incident{} not gated (--fail-on-incident {})", ungated,
                              ungated == 1 ? "" : "s", incidentGateText(policy.incidents)));
  }
  if (unchanged > 0) {
    why.push_back(fmt::format("{} unchanged incident{}", unchanged, unchanged == 1 ? "" : "s"));
  }
  if (unchecked && policy.allow_empty) why.emplace_back("--allow-empty");
  return fmt::format("{}", fmt::join(why, ", "));
}

bool diffFails(const CaptureDiff& diff, Severity fail_on, bool never,
               const IncidentGate& incidents) {
  const bool finding =
      !never && std::any_of(diff.added.begin(), diff.added.end(),
                            [&](const ReportedFinding& f) { return f.severity >= fail_on; });
  return finding || std::any_of(diff.incidents_added.begin(), diff.incidents_added.end(),
                                [&](const ReportedIncident& i) {
                                  return incidents.gates(i.fingerprint.kind);
                                });
}

report::Verdict PolicyJudge::verdict(const CaptureReport& report) const {
  return judgeCapture(policy_, report).verdict;
}

int PolicyJudge::exitStatus(const CaptureReport& report) const {
  return judgeCapture(policy_, report).exit_status;
}

bool PolicyJudge::failsUnchecked(const CaptureReport& report) const {
  return exitStatus(report) == kExitNoServo;
}

bool PolicyJudge::failsFinding(Severity severity) const {
  return !policy_.never && severity >= policy_.fail_on;
}

bool PolicyJudge::failsIncident(const CaptureReport& report, std::size_t index) const {
  return incidentGated(report, index, policy_.incidents);
}

report::RunStatus PolicyJudge::runStatus(const std::vector<CaptureReport>& reports) const {
  int status = kExitOk;
  for (const CaptureReport& r : reports) status = moreSerious(status, exitStatus(r));
  if (report::ReportWriter::interrupted()) {
    return {kExitInterrupted, true, "Ctrl-C; only the captures finished"};
  }
  return {status, false, exitReason(policy_, reports, status)};
}

}  // namespace ncservo::cli
