// `validate --format junit`: one test suite per capture, one test case per rule, and one for a
// layout that does not fit.
#include <fmt/format.h>

#include <pugixml.hpp>
#include <sstream>

#include "report_format.hpp"

namespace ncservo::cli::detail {

// One test case per rule (GitLab keys a case by classname and name and shows classname as its
// suite): failed when the rule fired at or above --fail-on, skipped where it was not judged.
void writeJunit(const ReportSink& sink, const std::vector<CaptureReport>& reports) {
  pugi::xml_document doc;
  auto decl = doc.append_child(pugi::node_declaration);
  decl.append_attribute("version") = "1.0";
  decl.append_attribute("encoding") = "UTF-8";
  auto suites = doc.append_child("testsuites");
  suites.append_attribute("name") = "ncservo";
  std::size_t total_tests = 0, total_failures = 0, total_errors = 0;
  for (const CaptureReport& r : reports) {
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
      auto testcase = suite.append_child("testcase");
      testcase.append_attribute("classname") = (r.path + "." + partyName(rule.party)).c_str();
      testcase.append_attribute("name") = fmt::format("{} {}", rule.code, rule.slug).c_str();
      testcase.append_attribute("time") = "0";
      std::vector<const Finding*> fired;
      std::vector<BaselineState> states;
      for (std::size_t i = 0; i < r.findings.size(); ++i) {
        if (r.findings[i].rule != rule.id) continue;
        fired.push_back(&r.findings[i]);
        states.push_back(i < r.baseline_states.size() ? r.baseline_states[i] : BaselineState::None);
      }
      // Not judged is not a pass: a disabled rule, a capture that could not be read, and (for a
      // rule that did not fire) a capture where not every configured servo was decoded.
      std::string not_judged;
      if (!sink.policy.enabled[static_cast<std::size_t>(rule.id)]) {
        not_judged = rule.by_default == ByDefault::Off
                         ? "off by default (--enable or the configuration's [rules] enable)"
                         : "disabled (--disable or the configuration's [rules])";
      } else if (r.unopened()) {
        not_judged = "UNREADABLE: " + *r.error;
      } else if (fired.empty() && !r.coverage.complete()) {
        not_judged = "NO SERVO: " + r.coverage.reason;
      }
      if (!not_judged.empty()) {
        // The schema Jenkins and GitLab read has <skipped> hold text, not attributes.
        testcase.append_child("skipped").text() = not_judged.c_str();
        ++skipped;
        continue;
      }
      if (fired.empty()) continue;
      // A finding below --fail-on is listed, but does not fail the test case.
      bool failing = false;
      std::string body;
      std::size_t added = 0;
      for (std::size_t i = 0; i < fired.size(); ++i) {
        const Finding* f = fired[i];
        const bool counts = states[i] != BaselineState::Unchanged;
        added += states[i] == BaselineState::New ? 1 : 0;
        failing = failing || (counts && !sink.policy.never && f->severity >= sink.policy.fail_on);
        body += fmt::format(
            "frame {} (since {}) t={:.6f}s {} {} [{}]{}: {}\n", f->at.frame, f->since.frame,
            seconds(r, f->at), utcOf(r, f->at), axisLabel(r, f->axis), severityName(f->severity),
            states[i] == BaselineState::None ? std::string()
                                             : fmt::format(" [{}]", baselineStateName(states[i])),
            f->message);
      }
      auto node = testcase.append_child(failing ? "failure" : "system-out");
      if (failing) {
        ++failures;
        node.append_attribute("message") =
            fmt::format("{} finding{} of {} {}{}", fired.size(), fired.size() == 1 ? "" : "s",
                        rule.code, rule.slug,
                        r.baseline
                            ? fmt::format(" ({} new, {} unchanged)", added, fired.size() - added)
                            : std::string())
                .c_str();
        node.append_attribute("type") = rule.code;
      }
      node.text() = body.c_str();
    }
    // A configured or ENI layout that does not fit (docs/layout.md#a-layout-that-does-not-fit):
    // one more case whose output names each axis. It is no finding and sets no exit status, so
    // the case does not fail either.
    const bool misfit = !r.layout_warnings.empty();
    if (misfit) {
      auto testcase = suite.append_child("testcase");
      testcase.append_attribute("classname") = (r.path + ".layout").c_str();
      testcase.append_attribute("name") = "layout fits the data";
      testcase.append_attribute("time") = "0";
      std::string body;
      for (const std::string& warning : r.layout_warnings) body += warning + "\n";
      testcase.append_child("system-out").text() = body.c_str();
    }
    if (r.error) {
      auto testcase = suite.append_child("testcase");
      testcase.append_attribute("classname") = r.path.c_str();
      testcase.append_attribute("name") = "capture readable";
      auto error = testcase.append_child("error");
      error.append_attribute("message") = r.error->c_str();
      ++total_errors;
    }
    const std::size_t tests = kRules.size() + (misfit ? 1 : 0) + (r.error ? 1 : 0);
    suite.append_attribute("tests") = tests;
    suite.append_attribute("failures") = failures;
    suite.append_attribute("errors") = r.error ? 1 : 0;
    suite.append_attribute("skipped") = skipped;
    total_tests += tests;
    total_failures += failures;
  }
  suites.append_attribute("tests") = total_tests;
  suites.append_attribute("failures") = total_failures;
  suites.append_attribute("errors") = total_errors;
  std::ostringstream text;
  doc.save(text, "  ");
  std::fputs(text.str().c_str(), sink.out);
}

}  // namespace ncservo::cli::detail
