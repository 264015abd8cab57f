// What `ncservo validate` reports about one capture, and the five ways it writes it
// (INTERFACES.md: text, json, jsonl, junit, sarif). Presentation only.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/coverage.hpp"
#include "ncservo/finding.hpp"
#include "ncservo/frame_clock.hpp"
#include "ncservo/validator.hpp"

namespace ncservo::cli {

// A capture's outcome, as its exit status has it (INTERFACES.md: 3, 1, 4, 0).
enum class Verdict { Unreadable, Fail, NoServo, Pass };

struct AxisReport {
  std::uint16_t index = 0;
  std::string name;
  std::optional<DriveState> state;
  std::vector<StateChange> timeline;
  std::uint64_t timeline_omitted = 0;
  std::vector<ErrorHistoryEntry> error_history;
  std::uint32_t telegram_failures = 0;
  std::optional<int> ready_mode;
};

// What a capture's snap length (or damage) cut off: the records cut short, and the frames where
// placed PDO regions were cut short or lay outside their datagram, with those axes' names.
struct Truncation {
  std::uint64_t snapped = 0;
  std::uint64_t first_snapped = 0;
  std::uint64_t cut_frames = 0;
  std::uint64_t first_cut = 0;
  std::vector<std::string> axes;
  bool any() const { return snapped > 0 || cut_frames > 0; }
};
// One line (stderr, the text report); empty when nothing was cut.
std::string describeTruncation(const Truncation& truncation);
Truncation truncationOf(std::uint64_t snapped, std::uint64_t first_snapped, const CutRegions& cut,
                        const std::vector<AxisInfo>& axes);

struct CaptureReport {
  std::string path;
  std::uint64_t frames = 0;
  std::uint64_t cycles = 0;
  std::int64_t first_time_ns = 0;
  CycleTimeSummary cycle_time;
  LayoutSource layout_source = LayoutSource::None;
  std::vector<AxisInfo> layout;
  std::vector<Finding> findings;        // kept only for the formats written at the end
  std::array<std::size_t, 3> counts{};  // findings by severity (Info, Warning, Error)
  std::vector<AxisReport> axes;
  std::optional<std::string> error;  // the capture could not be read to its end
  Coverage coverage;                 // whether every axis was checked
  TimestampSource timestamps = TimestampSource::Capture;
  ProbeCounts probe;
  std::string probe_note;  // FrameClock::note()
  Truncation truncation;
  std::vector<CaptureSegment> segments;  // listed ones (SegmentTracker::kMaxListed)
  std::uint64_t segment_count = 0;
  std::size_t count(Severity severity) const { return counts[static_cast<std::size_t>(severity)]; }
  // Whether any finding is at or above `level`.
  bool reaches(Severity level) const;
};

// Fills the end-of-capture parts of the report from the validator.
void summarise(const Validator& validator, CaptureReport& report);

// Where a report goes and when its findings fail it: at or above `fail_on`, unless `never`;
// a capture where not every axis was checked is "no servo" unless `allow_empty`.
struct ReportSink {
  std::FILE* out;
  Severity fail_on;
  bool never;
  bool allow_empty;
};
Verdict verdictOf(const ReportSink& sink, const CaptureReport& report);

// One output format of `validate` (INTERFACES.md): its name and its writers, called in the order
// beginCapture, finding (each), endCapture per capture, then finish. A null writer writes nothing.
struct ReportFormat {
  const char* name;
  // Streaming formats (text, JSON Lines) write each finding as it comes and keep none (constant
  // memory); the others write everything at the end.
  bool keeps_findings;
  void (*begin_capture)(const ReportSink& sink, const CaptureReport& report);
  void (*finding)(const ReportSink& sink, const CaptureReport& report, const Finding& finding);
  void (*end_capture)(const ReportSink& sink, const CaptureReport& report);
  void (*finish)(const ReportSink& sink, const std::vector<CaptureReport>& reports);
};

// The formats' names, in the order of the format table (for --format and its help).
std::vector<std::string> reportFormatNames();
// The format of that name; nullptr when there is none.
const ReportFormat* findReportFormat(std::string_view name);

class ReportWriter {
 public:
  ReportWriter(std::FILE* out, const ReportFormat& format, Severity fail_on, bool never,
               bool allow_empty = false);
  void beginCapture(const CaptureReport& report);
  void finding(const CaptureReport& report, const Finding& finding);
  void endCapture(const CaptureReport& report);
  void finish(const std::vector<CaptureReport>& reports);
  bool keepsFindings() const { return format_.keeps_findings; }
  Verdict verdict(const CaptureReport& report) const { return verdictOf(sink_, report); }

 private:
  ReportSink sink_;
  const ReportFormat& format_;
};

}  // namespace ncservo::cli
