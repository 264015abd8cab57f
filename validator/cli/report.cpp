#include "report.hpp"

#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <pugixml.hpp>
#include <sstream>

namespace ncservo::cli {

namespace {
using Json = nlohmann::ordered_json;

double seconds(const CaptureReport& r, const Stamp& at) {
  return static_cast<double>(at.time_ns - r.first_time_ns) / 1e9;
}

std::string axisName(const CaptureReport& r, std::uint16_t axis) {
  for (const AxisInfo& info : r.layout) {
    if (info.index == axis) return info.name;
  }
  return fmt::format("axis{}", axis);
}

std::string hex32(std::uint32_t v) {
  return fmt::format("0x{:08X}", v);
}

Json findingJson(const CaptureReport& r, const Finding& f) {
  const RuleDef& rule = ruleDef(f.rule);
  Json j;
  j["rule"] = rule.code;
  j["slug"] = rule.slug;
  j["severity"] = severityName(f.severity);
  j["axis"] = f.axis ? Json(*f.axis) : Json(nullptr);
  j["frame"] = f.at.frame;
  j["since_frame"] = f.since.frame;
  j["time"] = seconds(r, f.at);
  j["message"] = f.message;
  return j;
}

Json optionalNumber(const std::optional<double>& v) {
  return v ? Json(*v) : Json(nullptr);
}

const char* verdictName(Verdict v) {
  switch (v) {
    case Verdict::Unreadable:
      return "unreadable";
    case Verdict::Fail:
      return "fail";
    case Verdict::NoServo:
      return "no servo";
    case Verdict::Pass:
      return "pass";
  }
  return "pass";
}

// What the ESL probe headers said (PROTOCOL.md §8), when there were any.
Json probeJson(const CaptureReport& r) {
  const ProbeCounts& p = r.probe;
  Json j{{"frames", p.probed},
         {"timestamped", p.stamped},
         {"unstamped", p.unstamped},
         {"first_unstamped_frame", p.first_unstamped ? Json(p.first_unstamped) : Json(nullptr)},
         {"crc_errors", p.crc_errors},
         {"first_crc_error_frame", p.first_crc_error ? Json(p.first_crc_error) : Json(nullptr)},
         {"alignment_errors", p.alignment_errors}};
  if (!r.probe_note.empty()) j["note"] = r.probe_note;
  return j;
}

Json notJudgedJson(const CaptureReport& r) {
  Json list = Json::array();
  for (const NotJudged& n : r.coverage.not_judged) {
    list.push_back({{"rule", ruleDef(n.rule).code},
                    {"axis", n.axis ? Json(*n.axis) : Json(nullptr)},
                    {"reason", n.reason}});
  }
  return list;
}

Json truncationJson(const Truncation& t) {
  return {{"frames", t.snapped},
          {"first_frame", t.first_snapped ? Json(t.first_snapped) : Json(nullptr)},
          {"cut_pdo_frames", t.cut_frames},
          {"first_cut_pdo_frame", t.first_cut ? Json(t.first_cut) : Json(nullptr)},
          {"axes", t.axes}};
}

// The capture's segments (RULES.md "Time"), times in the capture's own seconds.
Json segmentsJson(const CaptureReport& r) {
  Json segments = Json::array();
  for (const CaptureSegment& s : r.segments) {
    segments.push_back({{"first_frame", s.first_frame},
                        {"last_frame", s.last_frame},
                        {"start", seconds(r, Stamp{s.first_frame, s.start_ns})},
                        {"end", seconds(r, Stamp{s.last_frame, s.end_ns})}});
  }
  return segments;
}

Json captureJson(const CaptureReport& r, Verdict verdict) {
  Json c;
  c["path"] = r.path;
  c["verdict"] = verdictName(verdict);
  if (!r.coverage.complete()) c["reason"] = r.coverage.reason;
  if (!r.coverage.missing.empty()) c["missing_axes"] = r.coverage.missing;
  c["frames"] = r.frames;
  c["cycles"] = r.cycles;
  c["cycle_time_us"] = {{"median", optionalNumber(r.cycle_time.median_us)},
                        {"p99", optionalNumber(r.cycle_time.p99_us)},
                        {"max", optionalNumber(r.cycle_time.max_us)}};
  Json layout_axes = Json::array();
  for (const AxisInfo& info : r.layout) {
    Json a{{"index", info.index}, {"name", info.name}};
    if (info.has_station) a["station"] = fmt::format("0x{:04X}", info.station);
    a["outputs"] = hex32(info.logical ? info.outputs : info.sm_outputs);
    a["inputs"] = hex32(info.logical ? info.inputs : info.sm_inputs);
    layout_axes.push_back(std::move(a));
  }
  c["timing"] = {{"timestamps", timestampSourceName(r.timestamps)}, {"segments", segmentsJson(r)}};
  if (r.segment_count > r.segments.size())
    c["timing"]["segments_omitted"] = r.segment_count - r.segments.size();
  if (r.probe.probed > 0 || !r.probe_note.empty()) c["probe"] = probeJson(r);
  if (r.truncation.any()) c["truncated"] = truncationJson(r.truncation);
  if (!r.coverage.not_judged.empty()) c["not_judged"] = notJudgedJson(r);
  c["layout"] = {{"source", layoutSourceName(r.layout_source)}, {"axes", std::move(layout_axes)}};
  Json findings = Json::array();
  for (const Finding& f : r.findings) findings.push_back(findingJson(r, f));
  c["findings"] = std::move(findings);
  Json axes = Json::array();
  for (const AxisReport& a : r.axes) {
    Json timeline = Json::array();
    for (const StateChange& s : a.timeline) {
      timeline.push_back({{"state", driveStateName(s.state)},
                          {"transition", s.transition ? Json(s.transition) : Json(nullptr)},
                          {"frame", s.at.frame},
                          {"time", seconds(r, s.at)}});
    }
    Json history = Json::array();
    for (const ErrorHistoryEntry& e : a.error_history) {
      history.push_back({{"code", e.cause->display},
                         {"canopen", fmt::format("0x{:04X}", e.cause->canopen)},
                         {"frame", e.at.frame},
                         {"time", seconds(r, e.at)}});
    }
    Json axis{{"index", a.index},
              {"name", a.name},
              {"state", a.state ? Json(driveStateName(*a.state)) : Json(nullptr)},
              {"state_timeline", std::move(timeline)}};
    if (a.timeline_omitted > 0) axis["state_timeline_omitted"] = a.timeline_omitted;
    axis["error_history"] = std::move(history);
    axis["telegram_failures"] = a.telegram_failures;
    axis["servo_ready_mode"] = a.ready_mode ? Json(*a.ready_mode) : Json(nullptr);
    axes.push_back(std::move(axis));
  }
  c["axes"] = std::move(axes);
  c["summary"] = {{"error", r.count(Severity::Error)},
                  {"warning", r.count(Severity::Warning)},
                  {"info", r.count(Severity::Info)}};
  if (r.error) c["error"] = *r.error;
  return c;
}

const char* sarifLevel(Severity s) {
  switch (s) {
    case Severity::Error:
      return "error";
    case Severity::Warning:
      return "warning";
    case Severity::Info:
      return "note";
  }
  return "note";
}

void writeSarif(const ReportSink& sink, const std::vector<CaptureReport>& reports) {
  Json rules = Json::array();
  for (const RuleDef& rule : kRules) {
    rules.push_back({{"id", rule.code},
                     {"name", rule.slug},
                     {"shortDescription", {{"text", rule.summary}}},
                     {"defaultConfiguration", {{"level", sarifLevel(rule.severity)}}},
                     {"properties", {{"party", partyName(rule.party)}, {"clause", rule.clause}}}});
  }
  Json results = Json::array();
  Json artifacts = Json::array();
  // A capture where not every axis was checked is a notification, not a result (SARIF 2.1.0
  // §3.58): nothing there was found, and nothing was shown to be right either.
  Json notifications = Json::array();
  for (std::size_t c = 0; c < reports.size(); ++c) {
    const CaptureReport& r = reports[c];
    artifacts.push_back({{"location", {{"uri", r.path}}}});
    if (!r.coverage.complete()) {
      notifications.push_back(
          {{"descriptor", {{"id", "NO-SERVO"}}},
           {"level", verdictOf(sink, r) == Verdict::NoServo ? "error" : "note"},
           {"message", {{"text", fmt::format("{}: NO SERVO: {}", r.path, r.coverage.reason)}}},
           {"locations",
            {{{"physicalLocation", {{"artifactLocation", {{"uri", r.path}, {"index", c}}}}}}}}});
    }
    for (const Finding& f : r.findings) {
      const RuleDef& rule = ruleDef(f.rule);
      const std::string axis = f.axis ? axisName(r, *f.axis) : std::string("bus");
      results.push_back(
          {{"ruleId", rule.code},
           {"ruleIndex", static_cast<std::size_t>(rule.id)},
           {"level", sarifLevel(f.severity)},
           {"message", {{"text", fmt::format("{} frame {}: {}", axis, f.at.frame, f.message)}}},
           {"locations",
            {{{"physicalLocation",
               {{"artifactLocation", {{"uri", r.path}, {"index", c}}},
                {"region", {{"startLine", 1}}}}},
              {"logicalLocations", {{{"name", axis}, {"kind", "object"}}}}}}},
           {"partialFingerprints",
            {{"ncservoFinding/v1", fmt::format("{}:{}:{}", rule.code, axis, f.since.frame)}}},
           {"properties",
            {{"frame", f.at.frame},
             {"since_frame", f.since.frame},
             {"time", seconds(r, f.at)},
             {"axis", f.axis ? Json(*f.axis) : Json(nullptr)}}}});
    }
  }
  Json sarif{{"$schema", "https://json.schemastore.org/sarif-2.1.0.json"},
             {"version", "2.1.0"},
             {"runs",
              {{{"tool",
                 {{"driver",
                   {{"name", "ncservo"},
                    {"version", NCSERVO_VERSION},
                    {"informationUri", "https://github.com/ncservo/ncservo"},
                    {"rules", std::move(rules)}}}}},
                {"artifacts", std::move(artifacts)},
                {"results", std::move(results)}}}}};
  if (!notifications.empty()) {
    sarif["runs"][0]["invocations"] = {
        {{"executionSuccessful", true}, {"toolExecutionNotifications", std::move(notifications)}}};
  }
  std::fputs((sarif.dump(2) + "\n").c_str(), sink.out);
}

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
    std::size_t failures = 0;
    std::size_t skipped = 0;
    for (const RuleDef& rule : kRules) {
      auto testcase = suite.append_child("testcase");
      testcase.append_attribute("classname") = (r.path + "." + partyName(rule.party)).c_str();
      testcase.append_attribute("name") = fmt::format("{} {}", rule.code, rule.slug).c_str();
      testcase.append_attribute("time") = "0";
      std::vector<const Finding*> fired;
      for (const Finding& f : r.findings) {
        if (f.rule == rule.id) fired.push_back(&f);
      }
      if (fired.empty()) {
        // Nothing checked is not a pass: where no servo (or not every configured one) was
        // decoded, a rule that did not fire is skipped, with the reason.
        if (!r.coverage.complete()) {
          testcase.append_child("skipped").append_attribute("message") =
              ("NO SERVO: " + r.coverage.reason).c_str();
          ++skipped;
        }
        continue;
      }
      // A finding below --fail-on is listed, but does not fail the test case.
      bool failing = false;
      std::string body;
      for (const Finding* f : fired) {
        failing = failing || (!sink.never && f->severity >= sink.fail_on);
        body +=
            fmt::format("frame {} (since {}) t={:.6f}s {} [{}]: {}\n", f->at.frame, f->since.frame,
                        seconds(r, f->at), f->axis ? axisName(r, *f->axis) : std::string("bus"),
                        severityName(f->severity), f->message);
      }
      auto node = testcase.append_child(failing ? "failure" : "system-out");
      if (failing) {
        ++failures;
        node.append_attribute("message") =
            fmt::format("{} finding{} of {} {}", fired.size(), fired.size() == 1 ? "" : "s",
                        rule.code, rule.slug)
                .c_str();
        node.append_attribute("type") = rule.code;
      }
      node.text() = body.c_str();
    }
    if (r.error) {
      auto testcase = suite.append_child("testcase");
      testcase.append_attribute("classname") = r.path.c_str();
      testcase.append_attribute("name") = "capture readable";
      auto error = testcase.append_child("error");
      error.append_attribute("message") = r.error->c_str();
      ++total_errors;
    }
    const std::size_t tests = kRules.size() + (r.error ? 1 : 0);
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

void writeTextHeading(const ReportSink& sink, const CaptureReport& r) {
  fmt::print(sink.out, "== {}\n", r.path);
}

void writeTextFinding(const ReportSink& sink, const CaptureReport& r, const Finding& f) {
  fmt::print(sink.out, "{:<7} {:<7} {} frame {} ({:.6f} s){}: {}\n", severityName(f.severity),
             ruleDef(f.rule).code, f.axis ? axisName(r, *f.axis) : std::string("bus"), f.at.frame,
             seconds(r, f.at),
             f.since.frame != f.at.frame ? fmt::format(", since frame {}", f.since.frame) : "",
             f.message);
}

void writeTextSummary(const ReportSink& sink, const CaptureReport& r) {
  std::FILE* out = sink.out;
  fmt::print(out, "{}: {} frames, {} cycles", r.path, r.frames, r.cycles);
  if (r.cycle_time.median_us) {
    fmt::print(out, ", cycle {:.1f} us (p99 {:.1f}, max {:.1f})", *r.cycle_time.median_us,
               r.cycle_time.p99_us.value_or(0), r.cycle_time.max_us.value_or(0));
  }
  fmt::print(out, "\nlayout: {}, {} ax{}\n", layoutSourceName(r.layout_source), r.layout.size(),
             r.layout.size() == 1 ? "is" : "es");
  // Where each axis was found: its station and its PDOs' logical (or SM) addresses.
  for (const AxisInfo& info : r.layout) {
    fmt::print(out, "  {}:", info.name);
    if (info.has_station) fmt::print(out, " station 0x{:04X},", info.station);
    if (info.logical) {
      fmt::print(out, " outputs 0x{:08X}, inputs 0x{:08X}\n", info.outputs, info.inputs);
    } else {
      fmt::print(out, " SM2 0x{:08X}, SM3 0x{:08X}\n", info.sm_outputs, info.sm_inputs);
    }
  }
  for (const AxisReport& a : r.axes) {
    fmt::print(out, "  {} (axis {}): {}; telegram failures {}", a.name, a.index,
               a.state ? driveStateName(*a.state) : "no inputs seen", a.telegram_failures);
    if (a.ready_mode) fmt::print(out, "; Servo_Ready_Mode {}", *a.ready_mode);
    fmt::print(out, "\n");
    for (const ErrorHistoryEntry& e : a.error_history) {
      fmt::print(out, "    error {} (0x{:04X}) at frame {}, {:.6f} s\n", e.cause->display,
                 e.cause->canopen, e.at.frame, seconds(r, e.at));
    }
  }
  fmt::print(out, "timestamps: {}\n", timestampSourceName(r.timestamps));
  if (r.segment_count > 1) {
    fmt::print(out, "segments: {} (timestamps jump back, or pause longer than capture_pause)\n",
               r.segment_count);
    for (const CaptureSegment& s : r.segments) {
      fmt::print(out, "  frames {}-{}, {:.6f} s to {:.6f} s\n", s.first_frame, s.last_frame,
                 seconds(r, Stamp{s.first_frame, s.start_ns}),
                 seconds(r, Stamp{s.last_frame, s.end_ns}));
    }
  }
  if (!r.probe_note.empty()) fmt::print(out, "probe: {}\n", r.probe_note);
  if (r.truncation.any()) fmt::print(out, "truncated: {}\n", describeTruncation(r.truncation));
  if (!r.coverage.not_judged.empty()) {
    // One line: rules by the reason and axes they share.
    std::vector<std::string> items;
    for (const NotJudged& n : r.coverage.not_judged) {
      items.push_back(fmt::format("{} ({})", ruleDef(n.rule).code,
                                  n.axis ? axisName(r, *n.axis) : std::string("bus")));
    }
    fmt::print(out, "not judged: {} - what they read was never captured\n", fmt::join(items, ", "));
  }
  if (!r.coverage.complete()) fmt::print(out, "NO SERVO: {}\n", r.coverage.reason);
  if (r.error) fmt::print(out, "error: {}\n", *r.error);
}

void writeTextVerdict(const ReportSink& sink, const std::vector<CaptureReport>& reports) {
  std::size_t counts[3] = {0, 0, 0};
  std::size_t unread = 0;     // captures that could not be read to their end
  std::size_t unchecked = 0;  // captures where not every axis was checked
  bool failed = false;
  bool no_servo = false;
  for (const CaptureReport& r : reports) {
    for (std::size_t s = 0; s < 3; ++s) counts[s] += r.counts[s];
    unread += r.error.has_value() ? 1 : 0;
    unchecked += r.coverage.complete() ? 0 : 1;
    const Verdict v = verdictOf(sink, r);
    failed = failed || v == Verdict::Fail || v == Verdict::Unreadable;
    no_servo = no_servo || v == Verdict::NoServo;
  }
  std::string notes;
  if (unread > 0) notes += fmt::format(", {} not read to the end", unread);
  if (unchecked > 0) {
    notes += fmt::format(", {} with no servo checked{}", unchecked,
                         sink.allow_empty ? " (--allow-empty)" : "");
  }
  fmt::print(sink.out,
             "verdict: {} - {} error{}, {} warning{}, {} info ({} capture{}{}, fail on {})\n",
             failed     ? "FAIL"
             : no_servo ? "NO SERVO"
                        : "PASS",
             counts[2], counts[2] == 1 ? "" : "s", counts[1], counts[1] == 1 ? "" : "s", counts[0],
             reports.size(), reports.size() == 1 ? "" : "s", notes,
             sink.never ? "never" : severityName(sink.fail_on));
}

void writeJson(const ReportSink& sink, const std::vector<CaptureReport>& reports) {
  Json j;
  j["tool"] = {{"name", "ncservo"}, {"version", NCSERVO_VERSION}};
  Json captures = Json::array();
  for (const CaptureReport& r : reports) captures.push_back(captureJson(r, verdictOf(sink, r)));
  j["captures"] = std::move(captures);
  std::fputs((j.dump(2) + "\n").c_str(), sink.out);
}

void writeJsonlFinding(const ReportSink& sink, const CaptureReport& r, const Finding& f) {
  Json j;
  j["capture"] = r.path;
  j.update(findingJson(r, f));
  std::fputs((j.dump() + "\n").c_str(), sink.out);
}

// JSON Lines: a capture where not every axis was checked closes with a line that says so.
// So does one with several segments.
void writeJsonlCoverage(const ReportSink& sink, const CaptureReport& r) {
  if (r.coverage.complete() && r.segment_count <= 1 && r.coverage.not_judged.empty() &&
      !r.truncation.any()) {
    return;
  }
  Json j{{"capture", r.path}, {"verdict", verdictName(verdictOf(sink, r))}};
  if (!r.coverage.complete()) j["reason"] = r.coverage.reason;
  if (!r.coverage.missing.empty()) j["missing_axes"] = r.coverage.missing;
  if (r.segment_count > 1) j["segments"] = segmentsJson(r);
  if (r.truncation.any()) j["truncated"] = truncationJson(r.truncation);
  if (!r.coverage.not_judged.empty()) j["not_judged"] = notJudgedJson(r);
  std::fputs((j.dump() + "\n").c_str(), sink.out);
}

// INTERFACES.md's formats of `validate`: name, keeps findings, begin capture, finding, end
// capture, finish.
const ReportFormat kReportFormats[] = {
    {"text", false, writeTextHeading, writeTextFinding, writeTextSummary, writeTextVerdict},
    {"json", true, nullptr, nullptr, nullptr, writeJson},
    {"jsonl", false, nullptr, writeJsonlFinding, writeJsonlCoverage, nullptr},
    {"junit", true, nullptr, nullptr, nullptr, writeJunit},
    {"sarif", true, nullptr, nullptr, nullptr, writeSarif},
};
}  // namespace

std::string describeTruncation(const Truncation& t) {
  std::string out;
  if (t.snapped > 0) {
    out = fmt::format("{} frame{} cut short by the capture's snap length (first: frame {})",
                      t.snapped, t.snapped == 1 ? "" : "s", t.first_snapped);
  }
  if (t.cut_frames > 0) {
    out += fmt::format("{}PDO words not captured in {} frame{} (first: frame {}) for {}",
                       out.empty() ? "" : "; ", t.cut_frames, t.cut_frames == 1 ? "" : "s",
                       t.first_cut, fmt::join(t.axes, ", "));
  }
  return out;
}

Truncation truncationOf(std::uint64_t snapped, std::uint64_t first_snapped, const CutRegions& cut,
                        const std::vector<AxisInfo>& axes) {
  Truncation t{snapped, first_snapped, cut.frames(), cut.firstFrame(), {}};
  for (std::uint16_t axis : cut.axes()) {
    t.axes.push_back(axis < axes.size() ? axes[axis].name : fmt::format("axis{}", axis));
  }
  return t;
}

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

bool CaptureReport::reaches(Severity level) const {
  for (std::size_t s = static_cast<std::size_t>(level); s < counts.size(); ++s) {
    if (counts[s] > 0) return true;
  }
  return false;
}

void summarise(const Validator& validator, CaptureReport& report) {
  report.cycles = validator.cycles();
  report.cycle_time = validator.cycleTime();
  report.layout_source = validator.decoder().source();
  report.layout = validator.decoder().axes();
  report.segments = validator.segments().segments();
  report.segment_count = validator.segments().count();
  report.axes.clear();
  for (std::size_t i = 0; i < validator.axisCount(); ++i) {
    const AxisModel* model = validator.axis(i);
    if (model == nullptr) continue;
    AxisReport a;
    a.index = model->index();
    a.name = axisName(report, model->index());
    a.state = model->state();
    a.timeline = model->timeline();
    a.timeline_omitted = model->timelineOmitted();
    a.error_history = model->errorHistory();
    a.telegram_failures = model->totalFailures();
    a.ready_mode = model->readyMode();
    report.axes.push_back(std::move(a));
  }
}

ReportWriter::ReportWriter(std::FILE* out, const ReportFormat& format, Severity fail_on, bool never,
                           bool allow_empty)
    : sink_{out, fail_on, never, allow_empty}, format_(format) {}

Verdict verdictOf(const ReportSink& sink, const CaptureReport& r) {
  if (r.error) return Verdict::Unreadable;
  if (!sink.never && r.reaches(sink.fail_on)) return Verdict::Fail;
  if (!r.coverage.complete() && !sink.allow_empty) return Verdict::NoServo;
  return Verdict::Pass;
}

void ReportWriter::beginCapture(const CaptureReport& report) {
  if (format_.begin_capture != nullptr) format_.begin_capture(sink_, report);
}

void ReportWriter::finding(const CaptureReport& report, const Finding& f) {
  if (format_.finding != nullptr) format_.finding(sink_, report, f);
}

void ReportWriter::endCapture(const CaptureReport& report) {
  if (format_.end_capture != nullptr) format_.end_capture(sink_, report);
}

void ReportWriter::finish(const std::vector<CaptureReport>& reports) {
  if (format_.finish != nullptr) format_.finish(sink_, reports);
  std::fflush(sink_.out);
}

}  // namespace ncservo::cli
