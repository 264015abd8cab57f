// What the report formats share (report.cpp) and the writers of the format table, one file per
// format: report_text.cpp, report_json.cpp (with the JSON that JSON Lines reuses),
// report_jsonl.cpp, report_junit.cpp, report_sarif.cpp, and html_report.cpp (declared in
// report.hpp).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/report/report.hpp"

namespace ncservo::report::detail {

using Json = nlohmann::ordered_json;

// The project's homepage (CMakeLists.txt): SARIF's informationUri, and the base of each rule's
// helpUri.
inline constexpr const char* kRepositoryUri = NCSERVO_HOMEPAGE_URL;

// The axis's configured name, or "axisN".
std::string axisName(const CaptureReport& r, std::uint16_t axis);
// Seconds since the capture's first frame, and the time in UTC at the capture's precision.
double seconds(const CaptureReport& r, const Stamp& at);
std::string utcOf(const CaptureReport& r, const Stamp& at);
// "10:41:07.123": the time of day, in UTC or local time (CaptureReport::zone), to the millisecond.
std::string dayTimeOf(const CaptureReport& r, const Stamp& at);
// "2024-05-01T10:41:05.888888Z": the capture's first frame, in its zone and precision.
std::string startOf(const CaptureReport& r);

// The JSON of one finding (with its state against a baseline, where there is one), one capture,
// and the parts JSON Lines repeats (report_json.cpp).
Json findingJson(const CaptureReport& r, const Finding& f, BaselineState state);
// A finding of a report read back (docs/baselines.md), as the report had it, with its `baseline`
// state ("absent", "new").
Json reportedFindingJson(const ReportedFinding& f, const char* state);
// `baseline` of a capture: the report, the capture matched and the counts.
Json baselineJson(const CaptureReport& r);
Json notJudgedJson(const CaptureReport& r);
Json truncationJson(const Truncation& t);
Json segmentsJson(const CaptureReport& r);
Json timingJson(const CaptureReport& r);
Json clockJson(const CaptureReport& r);
Json captureJson(const CaptureReport& r, Verdict verdict);
// One incident (docs/incidents.md, INTERFACES.md "Incidents"), as JSON and JSON Lines write it.
Json incidentJson(const CaptureReport& r, std::size_t index);
// docs/drive-messages.md: JSON `drive_messages`, `esc_errors` and `link_faults` items.
Json driveMessageJson(const CaptureReport& r, const DriveMessage& m);
Json escErrorJson(const CaptureReport& r, const EscErrorDelta& d);
Json linkFaultJson(const LinkFault& f);
// An incident's line ("axis1 fault E19 at frame 3040, 1.520 s — encoder: ..."), and its evidence
// and recovery lines, each starting with `indent` (report_text.cpp).
std::string incidentSummary(const CaptureReport& r, const Incident& incident);
std::string incidentDetails(const Incident& incident, std::string_view indent);
// "INC-encoder": the rule id SARIF and JUnit give an incident of that cause.
std::string incidentRuleId(CauseId cause);
// The baseline's incidents not seen again (JSON `baseline_absent_incidents`).
Json baselineAbsentIncidentsJson(const CaptureReport& r);

// docs/drive-messages.md: whether `slave` is the drive of axis `axis` in the layout (a drive of
// several axes is each one's), and whether it is any axis's drive.
bool slaveOfAxis(const CaptureReport& r, std::uint16_t axis, const SlaveRef& slave);
bool slaveIsAxis(const CaptureReport& r, const SlaveRef& slave);

// html_incidents.cpp: the HTML page's incident cards — their data, style and script
// (incidentCards(capture, section, index)).
Json incidentsHtmlJson(const CaptureReport& r);
extern const char* const kIncidentStyle;
extern const char* const kIncidentScript;

// The writers of the format table, by file: report_text.cpp
void writeTextHeading(const ReportSink& sink, const CaptureReport& r);
void writeTextFinding(const ReportSink& sink, const CaptureReport& r, const Finding& f,
                      BaselineState state);
void writeTextSummary(const ReportSink& sink, const CaptureReport& r);
// The incidents, a block per axis (docs/incidents.md#the-text-report); nothing when none.
void writeTextIncidents(std::FILE* out, const CaptureReport& r);
void writeTextVerdict(const ReportSink& sink, const std::vector<CaptureReport>& reports);
// report_json.cpp
void writeJson(const ReportSink& sink, const std::vector<CaptureReport>& reports);
// report_jsonl.cpp
void writeJsonlFinding(const ReportSink& sink, const CaptureReport& r, const Finding& f,
                       BaselineState state);
void writeJsonlCoverage(const ReportSink& sink, const CaptureReport& r);
// report_junit.cpp
void writeJunit(const ReportSink& sink, const std::vector<CaptureReport>& reports);
// report_sarif.cpp
void writeSarif(const ReportSink& sink, const std::vector<CaptureReport>& reports);
// html_report.cpp: the page's style, which `diff --format html` shares.
const char* htmlStyle();

}  // namespace ncservo::report::detail
