// The format table of `validate` and what its formats share; each format's writer is in a file of
// its own (report_format.hpp).
#include "report_format.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

namespace ncservo::report {

namespace detail {

std::string axisName(const CaptureReport& r, std::uint16_t axis) {
  for (const AxisInfo& info : r.layout) {
    if (info.index == axis) return info.name;
  }
  return fmt::format("axis{}", axis);
}

double seconds(const CaptureReport& r, const Stamp& at) {
  return static_cast<double>(at.time_ns - r.first_time_ns) / 1e9;
}

std::string utcOf(const CaptureReport& r, const Stamp& at) {
  return isoUtc(at.time_ns, r.timestamp_digits);
}

std::string dayTimeOf(const CaptureReport& r, const Stamp& at) {
  return timeOfDay(at.time_ns, r.zone);
}

std::string startOf(const CaptureReport& r) {
  return isoTime(r.first_time_ns, r.timestamp_digits, r.zone);
}

}  // namespace detail

using detail::axisName;
using detail::kRepositoryUri;

std::string axisLabel(const CaptureReport& r, const std::optional<std::uint16_t>& axis) {
  return axis ? axisName(r, *axis) : std::string("bus");
}

const char* verdictName(Verdict v) {
  switch (v) {
    case Verdict::Unreadable:
      return "unreadable";
    case Verdict::Fail:
      return "fail";
    case Verdict::NoServo:
      return "no servo";
    case Verdict::Warn:
      return "warn";
    case Verdict::Pass:
      return "pass";
  }
  return "pass";
}

std::string ruleAnchor(const RuleDef& rule) {
  std::string anchor(rule.code);
  std::transform(anchor.begin(), anchor.end(), anchor.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return anchor;
}

// An absolute address: SARIF's helpUri is a URI (the 2.1.0 schema's format "uri"), and a relative
// one would resolve against wherever the SARIF file is uploaded, not the repository.
std::string ruleHelpUri(const RuleDef& rule) {
  return fmt::format("{}/blob/main/docs/rules.md#{}", kRepositoryUri, ruleAnchor(rule));
}

namespace {
using namespace detail;

// The formats of `validate`, one writer file each (report_format.hpp).
const ReportFormat kReportFormats[] = {
    {.name = "text",
     .keeps_findings = false,
     .locates_frames = false,
     .draws_timelines = false,
     .begin_capture = writeTextHeading,
     .finding = writeTextFinding,
     .end_capture = writeTextSummary,
     .finish = writeTextVerdict},
    {.name = "json",
     .keeps_findings = true,
     .locates_frames = false,
     .draws_timelines = false,
     .begin_capture = nullptr,
     .finding = nullptr,
     .end_capture = nullptr,
     .finish = writeJson},
    {.name = "jsonl",
     .keeps_findings = false,
     .locates_frames = false,
     .draws_timelines = false,
     .begin_capture = nullptr,
     .finding = writeJsonlFinding,
     .end_capture = writeJsonlCoverage,
     .finish = nullptr},
    {.name = "junit",
     .keeps_findings = true,
     .locates_frames = false,
     .draws_timelines = false,
     .begin_capture = nullptr,
     .finding = nullptr,
     .end_capture = nullptr,
     .finish = writeJunit},
    {.name = "sarif",
     .keeps_findings = true,
     .locates_frames = true,
     .draws_timelines = false,
     .begin_capture = nullptr,
     .finding = nullptr,
     .end_capture = nullptr,
     .finish = writeSarif},
    {.name = "html",
     .keeps_findings = true,
     .locates_frames = false,
     .draws_timelines = true,
     .begin_capture = nullptr,
     .finding = nullptr,
     .end_capture = nullptr,
     .finish = writeHtml},
};

}  // namespace

std::vector<std::string> reportFormatNames() {
  std::vector<std::string> names;
  for (const ReportFormat& format : kReportFormats) names.emplace_back(format.name);
  return names;
}

const ReportFormat* findReportFormat(std::string_view name) {
  for (const ReportFormat& format : kReportFormats) {
    if (name == format.name) return &format;
  }
  return nullptr;
}

}  // namespace ncservo::report
