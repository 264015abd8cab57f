// `validate --format jsonl`: one line per finding as it comes, and each capture's closing lines.
#include <fmt/format.h>

#include <cstdio>

#include "report_format.hpp"

namespace ncservo::report {

std::string findingJsonLine(const CaptureReport& report, const Finding& finding,
                            BaselineState state) {
  detail::Json j;
  j["capture"] = report.path;
  j.update(detail::findingJson(report, finding, state));
  return j.dump();
}

std::string incidentJsonLine(const CaptureReport& report, std::size_t index) {
  return detail::Json{{"capture", report.path}, {"incident", detail::incidentJson(report, index)}}
      .dump();
}

std::string driveMessageJsonLine(const CaptureReport& report, const DriveMessage& message) {
  return detail::Json{{"capture", report.path},
                      {"drive_message", detail::driveMessageJson(report, message)}}
      .dump();
}

std::string linkFaultJsonLine(const CaptureReport& report, const LinkFault& fault) {
  return detail::Json{{"capture", report.path}, {"link_fault", detail::linkFaultJson(fault)}}
      .dump();
}

namespace detail {

void writeJsonlFinding(const ReportSink& sink, const CaptureReport& r, const Finding& f,
                       BaselineState state) {
  std::fputs((findingJsonLine(r, f, state) + "\n").c_str(), sink.out);
}

// JSON Lines: each capture closes with its timing line, after a line of its layout's warnings
// where it does not fit; one where not every axis was checked with a line that says so, and so
// does one with several segments.
void writeJsonlCoverage(const ReportSink& sink, const CaptureReport& r) {
  // Nothing was read: one line, its verdict and why (docs/cli.md#verdicts).
  if (r.unopened()) {
    const Json j{
        {"capture", r.path}, {"verdict", verdictName(sink.judge.verdict(r))}, {"reason", *r.error}};
    std::fputs((j.dump() + "\n").c_str(), sink.out);
    return;
  }
  // Against a baseline: a line per finding of it not seen again, then one with the counts.
  if (r.baseline) {
    for (const ReportedFinding& f : r.baseline_absent) {
      Json j{{"capture", r.path}};
      j.update(reportedFindingJson(f, "absent"));
      std::fputs((j.dump() + "\n").c_str(), sink.out);
    }
    std::fputs((Json{{"capture", r.path}, {"baseline", baselineJson(r)}}.dump() + "\n").c_str(),
               sink.out);
  }
  // A layout that does not fit, as JSON's `layout.warnings` (docs/layout.md).
  if (!r.layout_warnings.empty()) {
    const Json j{{"capture", r.path}, {"layout", {{"warnings", r.layout_warnings}}}};
    std::fputs((j.dump() + "\n").c_str(), sink.out);
  }
  // docs/incidents.md: one line per incident, once the capture has ended them.
  for (std::size_t i = 0; i < r.incidents.size(); ++i) {
    std::fputs((incidentJsonLine(r, i) + "\n").c_str(), sink.out);
  }
  if (r.baseline) {
    for (Json& absent : baselineAbsentIncidentsJson(r)) {
      const Json j{{"capture", r.path}, {"incident", std::move(absent)}};
      std::fputs((j.dump() + "\n").c_str(), sink.out);
    }
  }
  // docs/drive-messages.md: one line per drive message, counter rise and link fault.
  for (const DriveMessage& m : r.drive_messages) {
    std::fputs((driveMessageJsonLine(r, m) + "\n").c_str(), sink.out);
  }
  for (const EscErrorDelta& d : r.esc_errors) {
    const Json j{{"capture", r.path}, {"esc_error", escErrorJson(r, d)}};
    std::fputs((j.dump() + "\n").c_str(), sink.out);
  }
  for (const LinkFault& f : r.link_faults) {
    std::fputs((linkFaultJsonLine(r, f) + "\n").c_str(), sink.out);
  }
  const Json timing{{"capture", r.path},
                    {"timing", timingJson(r)},
                    {"clock", clockJson(r)},
                    {"duplicates", r.duplicates.count}};
  std::fputs((timing.dump() + "\n").c_str(), sink.out);
  if (r.coverage.complete() && r.segment_count <= 1 && r.coverage.not_judged.empty() &&
      !r.truncation.any()) {
    return;
  }
  Json j{{"capture", r.path}, {"verdict", verdictName(sink.judge.verdict(r))}};
  if (!r.coverage.complete()) j["reason"] = r.coverage.reason;
  if (!r.coverage.missing.empty()) j["missing_axes"] = r.coverage.missing;
  if (r.segment_count > 1) j["segments"] = segmentsJson(r);
  if (r.truncation.any()) j["truncated"] = truncationJson(r.truncation);
  if (!r.coverage.not_judged.empty()) j["not_judged"] = notJudgedJson(r);
  std::fputs((j.dump() + "\n").c_str(), sink.out);
}

}  // namespace detail
}  // namespace ncservo::report
