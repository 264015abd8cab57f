// `validate --format junit`: one test suite per capture, one test case per rule, and one for a
// layout that does not fit.
#include <fmt/format.h>

#include <pugixml.hpp>
#include <sstream>

#include "report_format.hpp"

namespace ncservo::report::detail {

namespace {

// A capture's findings of one rule, each with its state against the baseline.
struct Fired {
  std::vector<const Finding*> findings;
  std::vector<BaselineState> states;
};

Fired firedBy(const CaptureReport& r, const RuleDef& rule) {
  Fired fired;
  for (std::size_t i = 0; i < r.findings.size(); ++i) {
    if (r.findings[i].rule != rule.id) continue;
    fired.findings.push_back(&r.findings[i]);
    fired.states.push_back(i < r.baseline_states.size() ? r.baseline_states[i]
                                                        : BaselineState::None);
  }
  return fired;
}

// Not judged is not a pass: a disabled rule, a capture that could not be read, and (for a rule
// that did not fire) a capture where not every configured servo was decoded. "" when judged.
std::string notJudgedReason(const ReportSink& sink, const CaptureReport& r, const RuleDef& rule,
                            bool fired) {
  if (!sink.options.enabled[static_cast<std::size_t>(rule.id)]) {
    return rule.by_default == ByDefault::Off
               ? "off by default (--enable or the configuration's [rules] enable)"
               : "disabled (--disable or the configuration's [rules])";
  }
  if (r.unopened()) return "UNREADABLE: " + *r.error;
  if (!fired && !r.coverage.complete()) return "NO SERVO: " + r.coverage.reason;
  return "";
}

enum class CaseResult : std::uint8_t { Passed, Failed, Skipped };

// A rule's findings in its test case: the output lists each; it fails when one at or above
// --fail-on counts (with a baseline, only new ones do).
CaseResult writeFindings(pugi::xml_node testcase, const ReportSink& sink, const CaptureReport& r,
                         const RuleDef& rule, const Fired& fired) {
  bool failing = false;
  std::string body;
  std::size_t added = 0;
  for (std::size_t i = 0; i < fired.findings.size(); ++i) {
    const Finding* f = fired.findings[i];
    const BaselineState state = fired.states[i];
    const bool counts = state != BaselineState::Unchanged;
    added += state == BaselineState::New ? 1 : 0;
    failing = failing || (counts && sink.judge.failsFinding(f->severity));
    body += fmt::format(
        "frame {} (since {}) t={:.6f}s {} {} [{}]{}: {}\n", f->at.frame, f->since.frame,
        seconds(r, f->at), utcOf(r, f->at), axisLabel(r, f->axis), severityName(f->severity),
        state == BaselineState::None ? std::string()
                                     : fmt::format(" [{}]", baselineStateName(state)),
        f->message);
  }
  auto node = testcase.append_child(failing ? "failure" : "system-out");
  if (failing) {
    const std::size_t count = fired.findings.size();
    node.append_attribute("message") =
        fmt::format("{} finding{} of {} {}{}", count, count == 1 ? "" : "s", rule.code, rule.slug,
                    r.baseline ? fmt::format(" ({} new, {} unchanged)", added, count - added)
                               : std::string())
            .c_str();
    node.append_attribute("type") = rule.code;
  }
  node.text() = body.c_str();
  return failing ? CaseResult::Failed : CaseResult::Passed;
}

// One test case per rule (GitLab keys a case by classname and name and shows classname as its
// suite): failed when the rule fired at or above --fail-on, skipped where it was not judged.
CaseResult writeRuleCase(pugi::xml_node suite, const ReportSink& sink, const CaptureReport& r,
                         const RuleDef& rule) {
  auto testcase = suite.append_child("testcase");
  testcase.append_attribute("classname") = (r.path + "." + partyName(rule.party)).c_str();
  testcase.append_attribute("name") = fmt::format("{} {}", rule.code, rule.slug).c_str();
  testcase.append_attribute("time") = "0";
  const Fired fired = firedBy(r, rule);
  const std::string not_judged = notJudgedReason(sink, r, rule, !fired.findings.empty());
  if (!not_judged.empty()) {
    // The schema Jenkins and GitLab read has <skipped> hold text, not attributes.
    testcase.append_child("skipped").text() = not_judged.c_str();
    return CaseResult::Skipped;
  }
  if (fired.findings.empty()) return CaseResult::Passed;
  // A finding below --fail-on is listed, but does not fail the test case.
  return writeFindings(testcase, sink, r, rule, fired);
}

// A configured or ENI layout that does not fit (docs/layout.md#a-layout-that-does-not-fit): one
// more case whose output names each axis. It is no finding and sets no exit status, so the case
// does not fail either.
void writeLayoutCase(pugi::xml_node suite, const CaptureReport& r) {
  auto testcase = suite.append_child("testcase");
  testcase.append_attribute("classname") = (r.path + ".layout").c_str();
  testcase.append_attribute("name") = "layout fits the data";
  testcase.append_attribute("time") = "0";
  std::string body;
  for (const std::string& warning : r.layout_warnings) body += warning + "\n";
  testcase.append_child("system-out").text() = body.c_str();
}

// One test case per incident (docs/incidents.md), named by its fingerprint so that a CI keeps
// it from run to run: failed when --fail-on-incident gates its kind (with a baseline, when new).
CaseResult writeIncidentCase(pugi::xml_node suite, const ReportSink& sink, const CaptureReport& r,
                             std::size_t index) {
  const Incident& incident = r.incidents[index];
  const std::string rule = incidentRuleId(incident.cause);
  auto testcase = suite.append_child("testcase");
  testcase.append_attribute("classname") = (r.path + ".incidents").c_str();
  testcase.append_attribute("name") =
      fmt::format("{} {}", rule, fingerprintText(r.fingerprintOf(incident))).c_str();
  testcase.append_attribute("time") = "0";
  const bool failing = sink.judge.failsIncident(r, index);
  const BaselineState state =
      index < r.incident_states.size() ? r.incident_states[index] : BaselineState::None;
  const std::string body = fmt::format(
      "{}{}\n{}", incidentSummary(r, incident),
      state == BaselineState::None ? std::string() : fmt::format(" [{}]", baselineStateName(state)),
      incidentDetails(incident, ""));
  auto node = testcase.append_child(failing ? "failure" : "system-out");
  if (failing) {
    node.append_attribute("message") = incidentSummary(r, incident).c_str();
    node.append_attribute("type") = rule.c_str();
  }
  node.text() = body.c_str();
  return failing ? CaseResult::Failed : CaseResult::Passed;
}

void writeErrorCase(pugi::xml_node suite, const CaptureReport& r) {
  auto testcase = suite.append_child("testcase");
  testcase.append_attribute("classname") = r.path.c_str();
  testcase.append_attribute("name") = "capture readable";
  auto error = testcase.append_child("error");
  error.append_attribute("message") = r.error->c_str();
}

struct SuiteCounts {
  std::size_t tests = 0;
  std::size_t failures = 0;
  std::size_t errors = 0;
};

// One test suite per capture: a case per rule, then one for a layout that does not fit and one
// for a capture that could not be read to its end.
SuiteCounts writeSuite(pugi::xml_node suites, const ReportSink& sink, const CaptureReport& r) {
  auto suite = suites.append_child("testsuite");
  suite.append_attribute("name") = r.path.c_str();
  if (r.baseline) {
    // docs/baselines.md: only new findings fail a test case.
    auto property = suite.append_child("properties").append_child("property");
    property.append_attribute("name") = "baseline";
    property.append_attribute("value") =
        fmt::format("{} ({})", describeBaseline(r), r.baseline_path).c_str();
  }
  std::size_t failures = 0;
  std::size_t skipped = 0;
  for (const RuleDef& rule : kRules) {
    const CaseResult result = writeRuleCase(suite, sink, r, rule);
    failures += result == CaseResult::Failed ? 1 : 0;
    skipped += result == CaseResult::Skipped ? 1 : 0;
  }
  for (std::size_t i = 0; i < r.incidents.size(); ++i) {
    failures += writeIncidentCase(suite, sink, r, i) == CaseResult::Failed ? 1 : 0;
  }
  const bool misfit = !r.layout_warnings.empty();
  if (misfit) writeLayoutCase(suite, r);
  if (r.error) writeErrorCase(suite, r);
  const std::size_t tests =
      kRules.size() + r.incidents.size() + (misfit ? 1 : 0) + (r.error ? 1 : 0);
  suite.append_attribute("tests") = tests;
  suite.append_attribute("failures") = failures;
  suite.append_attribute("errors") = r.error ? 1 : 0;
  suite.append_attribute("skipped") = skipped;
  return {tests, failures, r.error ? 1u : 0u};
}

}  // namespace

void writeJunit(const ReportSink& sink, const std::vector<CaptureReport>& reports) {
  pugi::xml_document doc;
  auto decl = doc.append_child(pugi::node_declaration);
  decl.append_attribute("version") = "1.0";
  decl.append_attribute("encoding") = "UTF-8";
  auto suites = doc.append_child("testsuites");
  suites.append_attribute("name") = "ncservo";
  SuiteCounts total;
  for (const CaptureReport& r : reports) {
    const SuiteCounts counts = writeSuite(suites, sink, r);
    total.tests += counts.tests;
    total.failures += counts.failures;
    total.errors += counts.errors;
  }
  suites.append_attribute("tests") = total.tests;
  suites.append_attribute("failures") = total.failures;
  suites.append_attribute("errors") = total.errors;
  std::ostringstream text;
  doc.save(text, "  ");
  std::fputs(text.str().c_str(), sink.out);
}

}  // namespace ncservo::report::detail
