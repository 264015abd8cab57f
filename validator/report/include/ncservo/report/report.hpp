// What `ncservo validate` reports about one capture, and the five ways it writes it
// (docs/cli.md: text, json, jsonl, junit, sarif), to one output or several. Presentation only.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/base/error.hpp"
#include "ncservo/base/wall_time.hpp"
#include "ncservo/capture/capture_reader.hpp"
#include "ncservo/incidents/incident.hpp"
#include "ncservo/layout/layout_inference.hpp"
#include "ncservo/layout/layout_window.hpp"
#include "ncservo/model/timing.hpp"
#include "ncservo/pipeline/capture_result.hpp"
#include "ncservo/report/baseline.hpp"
#include "ncservo/report/report_charts.hpp"
#include "ncservo/rules/coverage.hpp"
#include "ncservo/rules/finding.hpp"
#include "ncservo/rules/validator.hpp"
#include "ncservo/wire/frame_clock.hpp"

namespace ncservo::report {

// What a capture is, as a person reads it (docs/cli.md#verdicts): it describes the capture, not
// the gate --fail-on sets, which only decides the exit status.
enum class Verdict { Unreadable, Fail, NoServo, Warn, Pass };

// The findings of one rule on one axis (or the bus) in a capture: how many, the first and last.
struct FindingGroup {
  RuleId rule{};
  Severity severity{};
  std::optional<std::uint16_t> axis;
  std::uint64_t count = 0;
  std::uint64_t added = 0;  // of them new against the baseline (--baseline)
  Stamp first;
  Stamp last;
  std::string first_message;
};

// One line (stderr, the text report); empty when nothing was cut.
std::string describeTruncation(const Truncation& truncation);
// Where the layout became certain and the frames forgotten before it, never judged.
std::string describeLateLayout(const LateLayout& late);
// The layout learnt from a start-up the snap length cut: axes may be missing.
std::string describeStartupCut(std::uint64_t frames);
// What a report tells of a capture (`validate --axis`, `--only`, docs/cli.md#scope): the findings
// and incidents of the named axes (all when none is named), the bus's always; findings,
// incidents or both. What is left out is neither reported nor counted for the verdict.
struct ReportScope {
  std::vector<std::string> axes;  // axis names
  bool findings = true;
  bool incidents = true;
  bool limited() const { return !axes.empty() || !findings || !incidents; }
};
// "axes X, Y; incidents only": the scope, for the report's line about it.
std::string describeScope(const ReportScope& scope);

// A capture's result (capture_result.hpp) with what the report adds: where the capture is, its
// findings as counted and grouped, and what the report itself found out about the file.
struct CaptureReport : CaptureResult {
  std::string path;
  int timestamp_digits = 6;       // of a second, as the capture stores its timestamps
  TimeZone zone = TimeZone::Utc;  // of the times of day the text writes (--local-time)
  ReportScope scope;
  std::vector<Finding> findings;        // kept only for the formats written at the end
  std::array<std::size_t, 3> counts{};  // findings by severity (Info, Warning, Error)
  std::vector<FindingGroup> groups;     // by (rule, axis), in the order of their first finding
  // Where the frames of the kept findings are stored in the file (sorted by frame), where known.
  std::vector<std::pair<std::uint64_t, RecordSpan>> frame_spans;
  std::optional<std::string> error;  // the capture could not be read to its end
  std::int64_t last_time_ns = 0;     // the last frame's
  // What the HTML report draws around findings (when a format draws them).
  FindingTimelines timelines;
  // What the capture file says it dropped (pcapng interface statistics), if it says.
  std::optional<CaptureDrops> capture_drops;
  // Against a baseline (--baseline, docs/baselines.md): the matcher (none without a baseline),
  // the state of each kept finding (beside `findings`), the new findings by severity, how many
  // were unchanged, and the baseline's findings not seen again (after closeBaseline()).
  std::optional<BaselineMatcher> baseline;
  std::string baseline_path;
  std::vector<BaselineState> baseline_states;
  std::array<std::size_t, 3> new_counts{};
  std::size_t unchanged = 0;
  std::vector<ReportedFinding> baseline_absent;
  // The incidents against the baseline, after closeBaseline(): each one's state (beside
  // `incidents`), and the baseline's incidents not seen again.
  std::vector<BaselineState> incident_states;
  std::vector<ReportedIncident> baseline_absent_incidents;
  // Whether the scope reports what happened on `axis` (none: the bus).
  bool inScope(const std::optional<std::uint16_t>& axis) const;
  std::size_t count(Severity severity) const { return counts[static_cast<std::size_t>(severity)]; }
  // The findings that count for the verdict and the exit status: all of them, or with a
  // baseline the new ones.
  std::size_t counted(Severity severity) const {
    return (baseline ? new_counts : counts)[static_cast<std::size_t>(severity)];
  }
  std::size_t newCount() const { return new_counts[0] + new_counts[1] + new_counts[2]; }
  // Counts a finding, by severity and in its group; against a baseline, matches it.
  BaselineState tally(const Finding& finding);
  // The fingerprint of a finding of this capture, and of an incident.
  Fingerprint fingerprintOf(const Finding& finding) const;
  IncidentFingerprint fingerprintOf(const Incident& incident) const;
  // The capture's findings and incidents have all come: the incidents are matched, and the
  // baseline's not seen again are absent.
  void closeBaseline();
  // The capture could not be read at all: nothing in it was checked.
  bool unopened() const { return error.has_value() && frames == 0; }
  // Whether any finding that counts is at or above `level`.
  bool reaches(Severity level) const;
};

// "3 new, 12 unchanged, 1 absent": a capture against its baseline (docs/baselines.md).
std::string describeBaseline(const CaptureReport& report);

// What a JSON report would hold of the capture, as baselines and `ncservo diff` read it.
ReportedCapture reportedCaptureOf(const CaptureReport& report, Verdict verdict);

// An incident as one line, the comment `annotate` writes on its frame (docs/field.md#annotate):
// "INC-encoder axis1 fault E19 at frame 3040, … — encoder: …; evidence: …; recovery: …".
std::string incidentComment(const CaptureReport& report, const Incident& incident);
// Whether a packet comment is one incidentComment wrote (annotate replaces its own comments).
bool isIncidentComment(std::string_view comment);

// "fail", "warn", "pass", "no servo", "unreadable": as the JSON report names a verdict.
const char* verdictName(Verdict verdict);
// An axis's configured name ("axis3" when it has none), "bus" for none.
std::string axisLabel(const CaptureReport& report, const std::optional<std::uint16_t>& axis);

// The frames of the kept findings and of the incidents, sorted, each once (where SARIF places
// them: the capture layer's locateRecords).
std::vector<std::uint64_t> findingFrames(const CaptureReport& report);

// ISO 8601 in UTC of a capture time, with `digits` digits of the second
// ("2024-05-01T12:00:00.123456Z").
std::string isoUtc(std::int64_t time_ns, int digits);

// Seconds with six decimals, the digits `fmt::format("{:.6f}", ns / 1e9)` gives, written into
// `out` (at least kSecondsTextSize bytes); returns their end. A finding's line in the text report
// writes one; a storm of findings writes thousands a second.
inline constexpr std::size_t kSecondsTextSize = 32;
char* writeSeconds(std::int64_t ns, char* out);

// The anchor of a rule in docs/rules.md ("se-001"), and the address SARIF's helpUri gives it.
std::string ruleAnchor(const RuleDef& rule);
std::string ruleHelpUri(const RuleDef& rule);

// A finding's and an incident's object as a JSON Lines report writes its line (`monitor --mqtt`
// publishes the same): one line, without its line feed.
std::string findingJsonLine(const CaptureReport& report, const Finding& finding,
                            BaselineState state);
std::string incidentJsonLine(const CaptureReport& report, std::size_t index);
// What a drive said and a link fault, likewise (docs/drive-messages.md).
std::string driveMessageJsonLine(const CaptureReport& report, const DriveMessage& message);
std::string linkFaultJsonLine(const CaptureReport& report, const LinkFault& fault);

// How a report is written: every finding or one line per rule and axis, and the rules switched
// on (which JUnit lists as test cases).
struct ReportOptions {
  bool verbose = false;  // text: every finding, not one line per rule and axis
  std::array<bool, kRuleCount> enabled{};
};

// The exit status of a run and why, for the text report's last line.
struct RunStatus {
  int exit_status = 0;
  bool interrupted = false;  // Ctrl-C stopped the run (docs/cli.md#interrupted)
  std::string reason;        // "findings at or above --fail-on warning", …; may be empty
};

// What the command decides of a capture and of a run (docs/cli.md#verdicts, #exit-status): the
// formats show its decisions and take none. The command's --fail-on, --fail-on-incident and
// --allow-empty decide them (ncservo's cli/verdict.hpp).
class Judge {
 public:
  virtual ~Judge() = default;
  virtual Verdict verdict(const CaptureReport& report) const = 0;
  virtual int exitStatus(const CaptureReport& report) const = 0;
  // The capture fails the run because not every axis was checked.
  virtual bool failsUnchecked(const CaptureReport& report) const = 0;
  // A finding of that severity fails the run.
  virtual bool failsFinding(Severity severity) const = 0;
  // Incident `index` of the capture fails the run.
  virtual bool failsIncident(const CaptureReport& report, std::size_t index) const = 0;
  virtual RunStatus runStatus(const std::vector<CaptureReport>& reports) const = 0;
};

// Where a report goes, how it is written, and the decisions it shows.
struct ReportSink {
  std::FILE* out;
  const ReportOptions& options;
  const Judge& judge;
};

// One output format of `validate` (docs/cli.md): its name and its writers, called in the order
// beginCapture, finding (each), endCapture per capture, then finish. A null writer writes nothing.
struct ReportFormat {
  const char* name;
  // Streaming formats (text, JSON Lines) write each finding as it comes and keep none (constant
  // memory); the others write everything at the end.
  bool keeps_findings;
  // The format names where each finding's frame is stored in the file (SARIF regions).
  bool locates_frames;
  // The format draws the bits around findings (CaptureReport::timelines, fed by the frames).
  bool draws_timelines;
  void (*begin_capture)(const ReportSink& sink, const CaptureReport& report);
  void (*finding)(const ReportSink& sink, const CaptureReport& report, const Finding& finding,
                  BaselineState state);
  void (*end_capture)(const ReportSink& sink, const CaptureReport& report);
  void (*finish)(const ReportSink& sink, const std::vector<CaptureReport>& reports);
};

// `validate --format html` (html_report.cpp): one self-contained page with the verdict and counts,
// a findings table that sorts and filters, each drawn finding's bit timeline, each axis's state
// timeline and error history, and the cycle-time histogram; Chart.js (Debian's libjs-chart.js) is
// inlined at build time, so the page fetches nothing when it opens.
void writeHtml(const ReportSink& sink, const std::vector<CaptureReport>& reports);

// The formats' names, in the order of the format table (for --format and its help).
std::vector<std::string> reportFormatNames();
// The format of that name; nullptr when there is none.
const ReportFormat* findReportFormat(std::string_view name);

// A report to write: its format and its file ("" or "-": standard output).
struct ReportTarget {
  const ReportFormat* format;
  std::string path;
};

// Writes every report of a run. A file is written to a temporary file beside it and renamed over
// it by finish(), so an interrupted run leaves no half report; one never finished is removed.
class ReportWriter {
 public:
  // `judge` outlives the writer.
  static Result<std::unique_ptr<ReportWriter>> open(const std::vector<ReportTarget>& targets,
                                                    const ReportOptions& options,
                                                    const Judge& judge);
  ~ReportWriter();
  ReportWriter(const ReportWriter&) = delete;
  ReportWriter& operator=(const ReportWriter&) = delete;

  void beginCapture(const CaptureReport& report);
  void finding(const CaptureReport& report, const Finding& finding, BaselineState state);
  void endCapture(const CaptureReport& report);
  Status finish(const std::vector<CaptureReport>& reports);
  bool keepsFindings() const;
  bool locatesFrames() const;
  bool drawsTimelines() const;
  const Judge& judge() const { return judge_; }

  // docs/cli.md#interrupted: from here on the first Ctrl-C (SIGINT) only asks the run to stop
  // (interrupted() turns true), so that the reports of the captures finished can still be
  // written; a second one ends the run at once, its temporary reports removed.
  void stopOnInterrupt();
  static const std::atomic<bool>& interrupted();

 private:
  struct Output {
    const ReportFormat* format;
    std::FILE* out;
    std::string path;       // the report's file; empty for standard output
    std::string temporary;  // where it is written until finish()
  };
  ReportWriter(const ReportOptions& options, const Judge& judge)
      : options_(options), judge_(judge) {}
  ReportOptions options_;
  const Judge& judge_;
  std::vector<Output> outputs_;
};

}  // namespace ncservo::report
