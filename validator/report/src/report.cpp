#include "ncservo/report/report.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <iterator>
#include <nlohmann/json.hpp>
#include <pugixml.hpp>
#include <sstream>

#include "ncservo/model/timing_text.hpp"

namespace ncservo::cli {

namespace {
std::string axisName(const CaptureReport& r, std::uint16_t axis) {
  for (const AxisInfo& info : r.layout) {
    if (info.index == axis) return info.name;
  }
  return fmt::format("axis{}", axis);
}
}  // namespace

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
    case Verdict::Pass:
      return "pass";
  }
  return "pass";
}

namespace {
using Json = nlohmann::ordered_json;

// The project's homepage (CMakeLists.txt): SARIF's informationUri, and the base of each rule's
// helpUri.
constexpr const char* kRepositoryUri = NCSERVO_HOMEPAGE_URL;

double seconds(const CaptureReport& r, const Stamp& at) {
  return static_cast<double>(at.time_ns - r.first_time_ns) / 1e9;
}

std::string utcOf(const CaptureReport& r, const Stamp& at) {
  return isoUtc(at.time_ns, r.timestamp_digits);
}

std::string hex16(std::uint16_t v) {
  return fmt::format("0x{:04X}", v);
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
  j["axis_name"] = f.axis ? Json(axisName(r, *f.axis)) : Json(nullptr);
  j["frame"] = f.at.frame;
  j["since_frame"] = f.since.frame;
  j["time"] = seconds(r, f.at);
  j["time_utc"] = utcOf(r, f.at);
  j["message"] = f.message;
  return j;
}

Json optionalNumber(const std::optional<double>& v) {
  return v ? Json(*v) : Json(nullptr);
}

// The verdicts as text shouts them.
const char* verdictHeadline(Verdict v) {
  switch (v) {
    case Verdict::Unreadable:
      return "UNREADABLE";
    case Verdict::Fail:
      return "FAIL";
    case Verdict::NoServo:
      return "NO SERVO";
    case Verdict::Pass:
      break;
  }
  return "PASS";
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

// Microseconds, to the nanosecond.
double microseconds(double ns) {
  return std::round(ns) / 1000.0;
}

Json seriesJson(const std::optional<SeriesSummary>& series) {
  if (!series) return nullptr;
  const SeriesSummary& s = *series;
  Json histogram = Json::array();
  for (const HistogramBin& bin : s.histogram) {
    histogram.push_back({{"from_us", microseconds(static_cast<double>(bin.from_ns))},
                         {"to_us", microseconds(static_cast<double>(bin.to_ns))},
                         {"count", bin.count}});
  }
  auto us = [](std::int64_t ns) { return microseconds(static_cast<double>(ns)); };
  return {{"count", s.count},
          {"min", us(s.min_ns)},
          {"median", us(s.median_ns)},
          {"mean", microseconds(s.mean_ns)},
          {"stddev", microseconds(s.stddev_ns)},
          {"p1", us(s.p1_ns)},
          {"p99", us(s.p99_ns)},
          {"p999", us(s.p999_ns)},
          {"max", us(s.max_ns)},
          {"histogram", std::move(histogram)},
          {"under", s.under},
          {"over", s.over}};
}

Json worstJson(const std::vector<TimedFrames>& worst, const char* since_key,
               const char* value_key) {
  Json list = Json::array();
  for (const TimedFrames& w : worst) {
    list.push_back({{"frame", w.frame},
                    {since_key, w.since_frame},
                    {value_key, microseconds(static_cast<double>(w.ns))}});
  }
  return list;
}

// The process-data datagrams whose cyclic frames the bus rules judged (docs/timing.md).
Json cyclicDatagramsJson(const CaptureReport& r) {
  Json list = Json::array();
  for (const CyclicDatagram& d : r.cyclic_datagrams) {
    list.push_back({{"command", ecat::commandName(d.command)},
                    {"address", hex32(d.address)},
                    {"length", d.length},
                    {"frames", d.frames}});
  }
  return list;
}

// INTERFACES.md `timing.dc`: one entry per slave whose distributed clock was read.
Json dcJson(const CaptureReport& r) {
  Json list = Json::array();
  for (const DcStation& s : r.dc) {
    Json difference = nullptr;
    if (s.last_difference_ns) {
      difference = {{"last", *s.last_difference_ns},
                    {"max_abs", s.max_abs_difference_ns},
                    {"reads", s.difference_reads}};
    }
    auto ppm = [](const std::optional<double>& v) {
      // To the thousandth of a ppm; + 0.0 writes a negative zero as 0.0.
      return v ? Json(std::round(*v * 1000.0) / 1000.0 + 0.0) : Json(nullptr);
    };
    list.push_back({{"station", s.slave.station ? Json(hex16(*s.slave.station)) : Json(nullptr)},
                    {"ring_position", s.slave.position ? Json(*s.slave.position) : Json(nullptr)},
                    {"reference", s.reference},
                    {"samples", s.time_reads},
                    {"drift_ppm", ppm(s.drift_ppm)},
                    {"drift_first_half_ppm", ppm(s.first_half_ppm)},
                    {"drift_second_half_ppm", ppm(s.second_half_ppm)},
                    {"systime_diff_ns", std::move(difference)},
                    {"settled_frame", s.settled_frame ? Json(*s.settled_frame) : Json(nullptr)}});
  }
  return list;
}

// INTERFACES.md `timing`.
Json timingJson(const CaptureReport& r) {
  Json timing{
      {"timestamps", timestampSourceName(r.timestamps)},
      {"resolution_ns", timestampResolutionNs(r.timestamps, r.timestamp_digits)},
      {"cycle_us", seriesJson(r.timing.cycle)},
      {"latency_us", seriesJson(r.timing.latency)},
      {"worst_cycles", worstJson(r.timing.worst_cycles, "since_frame", "interval_us")},
      {"worst_latencies", worstJson(r.timing.worst_latencies, "master_frame", "latency_us")},
      {"segments", segmentsJson(r)},
      {"cyclic_datagrams", cyclicDatagramsJson(r)}};
  if (r.unfollowed_frames > 0) timing["frames_not_followed"] = r.unfollowed_frames;
  if (r.segment_count > r.segments.size())
    timing["segments_omitted"] = r.segment_count - r.segments.size();
  timing["dc"] = dcJson(r);
  return timing;
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
    if (info.has_station) a["station"] = hex16(info.station);
    a["outputs"] = hex32(info.logical ? info.outputs : info.sm_outputs);
    a["inputs"] = hex32(info.logical ? info.inputs : info.sm_inputs);
    layout_axes.push_back(std::move(a));
  }
  c["timing"] = timingJson(r);
  if (r.probe.probed > 0 || !r.probe_note.empty()) c["probe"] = probeJson(r);
  if (r.truncation.any()) c["truncated"] = truncationJson(r.truncation);
  if (!r.coverage.not_judged.empty()) c["not_judged"] = notJudgedJson(r);
  c["layout"] = {{"source", layoutSourceName(r.layout_source)}, {"axes", std::move(layout_axes)}};
  if (r.startup_frames_cut > 0) c["layout"]["startup_frames_cut"] = r.startup_frames_cut;
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
                          {"time", seconds(r, s.at)},
                          {"time_utc", utcOf(r, s.at)}});
    }
    Json history = Json::array();
    for (const ErrorHistoryEntry& e : a.error_history) {
      history.push_back({{"code", e.cause->display},
                         {"canopen", hex16(e.cause->canopen)},
                         {"frame", e.at.frame},
                         {"time", seconds(r, e.at)},
                         {"time_utc", utcOf(r, e.at)}});
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

// A capture is a notification, not a result (SARIF 2.1.0 §3.58), where it could not be read to its
// end or not every axis was checked: nothing there was found, nor shown to be right.
void addNotifications(const ReportSink& sink, const CaptureReport& r, std::size_t artifact,
                      Json& notifications) {
  const Json where = {
      {{"physicalLocation", {{"artifactLocation", {{"uri", r.path}, {"index", artifact}}}}}}};
  if (r.error) {
    notifications.push_back({{"descriptor", {{"id", "UNREADABLE"}}},
                             {"level", "error"},
                             {"message", {{"text", fmt::format("{}: {}", r.path, *r.error)}}},
                             {"locations", where}});
  }
  if (!r.coverage.complete()) {
    notifications.push_back(
        {{"descriptor", {{"id", "NO-SERVO"}}},
         {"level", verdictOf(sink.policy, r) == Verdict::NoServo ? "error" : "note"},
         {"message", {{"text", fmt::format("{}: NO SERVO: {}", r.path, r.coverage.reason)}}},
         {"locations", where}});
  }
}

// A finding's place: the capture, the region of the file that stores its frame where that is
// known (a pcap has no lines), and the frame as a logical location (an element of the capture).
Json sarifLocation(const CaptureReport& r, std::size_t artifact, const Finding& f) {
  Json physical{{"artifactLocation", {{"uri", r.path}, {"index", artifact}}}};
  const auto stored = std::lower_bound(r.frame_spans.begin(), r.frame_spans.end(), f.at.frame,
                                       [](const std::pair<std::uint64_t, RecordSpan>& s,
                                          std::uint64_t frame) { return s.first < frame; });
  if (stored != r.frame_spans.end() && stored->first == f.at.frame) {
    physical["region"] = {{"byteOffset", stored->second.offset},
                          {"byteLength", stored->second.length}};
  }
  const std::string frame = fmt::format("frame {}", f.at.frame);
  return {{"physicalLocation", std::move(physical)},
          {"logicalLocations",
           {{{"name", frame},
             {"fullyQualifiedName", fmt::format("{}/{}", r.path, frame)},
             {"kind", "element"}}}}};
}

void writeSarif(const ReportSink& sink, const std::vector<CaptureReport>& reports) {
  Json rules = Json::array();
  for (const RuleDef& rule : kRules) {
    rules.push_back({{"id", rule.code},
                     {"name", rule.slug},
                     {"shortDescription", {{"text", rule.summary}}},
                     {"helpUri", ruleHelpUri(rule)},
                     {"defaultConfiguration", {{"level", sarifLevel(rule.severity)}}},
                     {"properties", {{"party", partyName(rule.party)}, {"clause", rule.clause}}}});
  }
  Json results = Json::array();
  Json artifacts = Json::array();
  Json notifications = Json::array();
  bool all_read = true;
  for (std::size_t c = 0; c < reports.size(); ++c) {
    const CaptureReport& r = reports[c];
    artifacts.push_back({{"location", {{"uri", r.path}}}});
    addNotifications(sink, r, c, notifications);
    all_read = all_read && !r.error;
    for (const Finding& f : r.findings) {
      const RuleDef& rule = ruleDef(f.rule);
      const std::string axis = axisLabel(r, f.axis);
      results.push_back(
          {{"ruleId", rule.code},
           {"ruleIndex", static_cast<std::size_t>(&rule - kRules.data())},
           {"level", sarifLevel(f.severity)},
           {"message", {{"text", fmt::format("{} frame {}: {}", axis, f.at.frame, f.message)}}},
           {"locations", {sarifLocation(r, c, f)}},
           {"partialFingerprints",
            {{"ncservoFinding/v1", fmt::format("{}:{}:{}", rule.code, axis, f.since.frame)}}},
           {"properties",
            {{"frame", f.at.frame},
             {"since_frame", f.since.frame},
             {"time", seconds(r, f.at)},
             {"time_utc", utcOf(r, f.at)},
             {"axis", f.axis ? Json(*f.axis) : Json(nullptr)},
             {"axis_name", f.axis ? Json(axis) : Json(nullptr)}}}});
    }
  }
  // executionSuccessful (§3.20.14): false where a capture could not be read (exit status 3).
  Json invocation{{"executionSuccessful", all_read}};
  if (!notifications.empty()) invocation["toolExecutionNotifications"] = std::move(notifications);
  Json sarif{{"$schema", "https://json.schemastore.org/sarif-2.1.0.json"},
             {"version", "2.1.0"},
             {"runs",
              {{{"tool",
                 {{"driver",
                   {{"name", "ncservo"},
                    {"version", NCSERVO_VERSION},
                    {"informationUri", kRepositoryUri},
                    {"rules", std::move(rules)}}}}},
                {"invocations", {std::move(invocation)}},
                {"artifacts", std::move(artifacts)},
                {"results", std::move(results)}}}}};
  std::fputs((sarif.dump(2) + "\n").c_str(), sink.out);
}

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
      for (const Finding* f : fired) {
        failing = failing || (!sink.policy.never && f->severity >= sink.policy.fail_on);
        body += fmt::format("frame {} (since {}) t={:.6f}s {} {} [{}]: {}\n", f->at.frame,
                            f->since.frame, seconds(r, f->at), utcOf(r, f->at),
                            axisLabel(r, f->axis), severityName(f->severity), f->message);
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
  if (!sink.policy.verbose) return;
  fmt::print(sink.out, "{:<7} {:<7} {} frame {} ({:.6f} s){}: {}\n", severityName(f.severity),
             ruleDef(f.rule).code, axisLabel(r, f.axis), f.at.frame, seconds(r, f.at),
             f.since.frame != f.at.frame ? fmt::format(", since frame {}", f.since.frame) : "",
             f.message);
}

// One line per rule and axis: how many findings, the first and last frame, the first message.
void writeTextGroups(const ReportSink& sink, const CaptureReport& r) {
  for (const FindingGroup& g : r.groups) {
    const std::string first = fmt::format("{} ({:.6f} s)", g.first.frame, seconds(r, g.first));
    fmt::print(sink.out, "{:<7} {:<7} {} {} finding{}, {}: {}\n", severityName(g.severity),
               ruleDef(g.rule).code, axisLabel(r, g.axis), g.count, g.count == 1 ? "" : "s",
               g.count == 1 ? "frame " + first
                            : fmt::format("frames {} to {} ({:.6f} s), first", first, g.last.frame,
                                          seconds(r, g.last)),
               g.first_message);
  }
}

// One line: the datagrams whose cyclic frames the bus rules judged.
std::string describeCyclicDatagrams(const CaptureReport& r) {
  std::vector<std::string> items;
  for (const CyclicDatagram& d : r.cyclic_datagrams) {
    items.push_back(fmt::format("{} 0x{:08X} ({} byte{}, {} frames)", ecat::commandName(d.command),
                                d.address, d.length, d.length == 1 ? "" : "s", d.frames));
  }
  std::string line =
      fmt::format("cyclic datagrams judged: {}",
                  items.empty() ? "none" : fmt::format("{}", fmt::join(items, ", ")));
  if (r.unfollowed_frames > 0) {
    line += fmt::format(" ({} frames of further cyclic frames not followed)", r.unfollowed_frames);
  }
  return line;
}

void writeTextSummary(const ReportSink& sink, const CaptureReport& r) {
  std::FILE* out = sink.out;
  if (!sink.policy.verbose) writeTextGroups(sink, r);
  fmt::print(out, "{}: {} frames, {} cycles", r.path, r.frames, r.cycles);
  if (r.cycle_time.median_us) {
    fmt::print(out, ", cycle {:.1f} us (p99 {:.1f}, max {:.1f})", *r.cycle_time.median_us,
               r.cycle_time.p99_us.value_or(0), r.cycle_time.max_us.value_or(0));
  }
  fmt::print(out, "\nlayout: {}, {} ax{}\n", layoutSourceName(r.layout_source), r.layout.size(),
             r.layout.size() == 1 ? "is" : "es");
  if (r.startup_frames_cut > 0) {
    fmt::print(out, "  {}\n", describeStartupCut(r.startup_frames_cut));
  }
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
  std::fputs(timingText(r.timing, timestampSourceName(r.timestamps),
                        timestampResolutionNs(r.timestamps, r.timestamp_digits))
                 .c_str(),
             out);
  fmt::print(out, "{}\n", describeCyclicDatagrams(r));
  std::fputs(dcText(r.dc, r.dc_settled_ns).c_str(), out);
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
    // One line: the rules of each axis (or the bus), axes with the same rules named together.
    std::vector<std::pair<std::string, std::vector<std::string>>> groups;  // rules, axes
    std::optional<std::uint16_t> current;
    std::vector<std::string> codes;
    const auto close = [&] {
      if (codes.empty()) return;
      const std::string rules = fmt::format("{}", fmt::join(codes, ", "));
      const std::string who = current ? axisName(r, *current) : std::string("bus");
      auto same = std::find_if(groups.begin(), groups.end(),
                               [&](const auto& g) { return g.first == rules; });
      if (same == groups.end()) {
        groups.push_back({rules, {who}});
      } else {
        same->second.push_back(who);
      }
      codes.clear();
    };
    for (const NotJudged& n : r.coverage.not_judged) {
      if (!codes.empty() && n.axis != current) close();
      current = n.axis;
      codes.emplace_back(ruleDef(n.rule).code);
    }
    close();
    std::vector<std::string> items;
    for (const auto& [rules, who] : groups) {
      items.push_back(fmt::format("{}: {}", fmt::join(who, ", "), rules));
    }
    fmt::print(out, "not judged (what they read was never captured): {}\n", fmt::join(items, "; "));
  }
  if (!r.coverage.complete()) fmt::print(out, "NO SERVO: {}\n", r.coverage.reason);
  if (r.error) fmt::print(out, "error: {}\n", *r.error);
  fmt::print(out, "capture verdict: {} - {} error{}, {} warning{}, {} info ({})\n",
             verdictHeadline(verdictOf(sink.policy, r)), r.count(Severity::Error),
             r.count(Severity::Error) == 1 ? "" : "s", r.count(Severity::Warning),
             r.count(Severity::Warning) == 1 ? "" : "s", r.count(Severity::Info), r.path);
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
    const Verdict v = verdictOf(sink.policy, r);
    failed = failed || v == Verdict::Fail || v == Verdict::Unreadable;
    no_servo = no_servo || v == Verdict::NoServo;
  }
  std::string notes;
  if (unread > 0) notes += fmt::format(", {} not read to the end", unread);
  if (unchecked > 0) {
    notes += fmt::format(", {} with no servo checked{}", unchecked,
                         sink.policy.allow_empty ? " (--allow-empty)" : "");
  }
  fmt::print(sink.out,
             "verdict: {} - {} error{}, {} warning{}, {} info ({} capture{}{}, fail on {})\n",
             failed     ? "FAIL"
             : no_servo ? "NO SERVO"
                        : "PASS",
             counts[2], counts[2] == 1 ? "" : "s", counts[1], counts[1] == 1 ? "" : "s", counts[0],
             reports.size(), reports.size() == 1 ? "" : "s", notes,
             sink.policy.never ? "never" : severityName(sink.policy.fail_on));
}

void writeJson(const ReportSink& sink, const std::vector<CaptureReport>& reports) {
  Json j;
  j["tool"] = {{"name", "ncservo"}, {"version", NCSERVO_VERSION}};
  Json captures = Json::array();
  for (const CaptureReport& r : reports)
    captures.push_back(captureJson(r, verdictOf(sink.policy, r)));
  j["captures"] = std::move(captures);
  std::fputs((j.dump(2) + "\n").c_str(), sink.out);
}

void writeJsonlFinding(const ReportSink& sink, const CaptureReport& r, const Finding& f) {
  Json j;
  j["capture"] = r.path;
  j.update(findingJson(r, f));
  std::fputs((j.dump() + "\n").c_str(), sink.out);
}

// JSON Lines: each capture closes with its timing line; one where not every axis was checked
// with a line that says so, and so does one with several segments.
void writeJsonlCoverage(const ReportSink& sink, const CaptureReport& r) {
  std::fputs((Json{{"capture", r.path}, {"timing", timingJson(r)}}.dump() + "\n").c_str(),
             sink.out);
  if (r.coverage.complete() && r.segment_count <= 1 && r.coverage.not_judged.empty() &&
      !r.truncation.any()) {
    return;
  }
  Json j{{"capture", r.path}, {"verdict", verdictName(verdictOf(sink.policy, r))}};
  if (!r.coverage.complete()) j["reason"] = r.coverage.reason;
  if (!r.coverage.missing.empty()) j["missing_axes"] = r.coverage.missing;
  if (r.segment_count > 1) j["segments"] = segmentsJson(r);
  if (r.truncation.any()) j["truncated"] = truncationJson(r.truncation);
  if (!r.coverage.not_judged.empty()) j["not_judged"] = notJudgedJson(r);
  std::fputs((j.dump() + "\n").c_str(), sink.out);
}

// INTERFACES.md's formats of `validate`: name, keeps findings, locates frames, draws timelines,
// begin capture, finding, end capture, finish.
const ReportFormat kReportFormats[] = {
    {"text", false, false, false, writeTextHeading, writeTextFinding, writeTextSummary,
     writeTextVerdict},
    {"json", true, false, false, nullptr, nullptr, nullptr, writeJson},
    {"jsonl", false, false, false, nullptr, writeJsonlFinding, writeJsonlCoverage, nullptr},
    {"junit", true, false, false, nullptr, nullptr, nullptr, writeJunit},
    {"sarif", true, true, false, nullptr, nullptr, nullptr, writeSarif},
    {"html", true, false, true, nullptr, nullptr, nullptr, writeHtml},
};

// Temporary reports are removed if the run is interrupted; the list is fixed while the handler
// may run (between ReportWriter::open and finish).
const std::vector<std::string>* g_temporaries = nullptr;

extern "C" void removeTemporaries(int signal) {
  if (g_temporaries != nullptr) {
    for (const std::string& path : *g_temporaries) ::unlink(path.c_str());
  }
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

constexpr int kInterrupts[] = {SIGINT, SIGTERM, SIGHUP, SIGPIPE};
// What each was before: a signal the caller ignores (nohup, a background job) stays ignored.
void (*g_previous[std::size(kInterrupts)])(int) = {};
}  // namespace

std::string describeStartupCut(std::uint64_t frames) {
  return fmt::format(
      "incomplete: the snap length cut {} start-up frame{} short; a servo configured after a cut "
      "is missing from this layout (give the layout with --config or --eni)",
      frames, frames == 1 ? "" : "s");
}

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
  report.timing = validator.bus().timing().summary();
  report.cyclic_datagrams = validator.bus().cyclicDatagrams();
  report.unfollowed_frames = validator.bus().unfollowedFrames();
  report.dc = validator.dc().stations();
  report.dc_settled_ns = validator.dc().settledNs();
  report.cycles = validator.cycles();
  report.cycle_time = validator.cycleTime();
  report.layout_source = validator.decoder().source();
  report.layout = validator.decoder().axes();
  if (report.layout_source == LayoutSource::Startup) {
    report.startup_frames_cut = validator.decoder().learner().configurationFramesCut();
  }
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

Verdict verdictOf(const ReportPolicy& policy, const CaptureReport& r) {
  if (r.error) return Verdict::Unreadable;
  if (!policy.never && r.reaches(policy.fail_on)) return Verdict::Fail;
  if (!r.coverage.complete() && !policy.allow_empty) return Verdict::NoServo;
  return Verdict::Pass;
}

void CaptureReport::tally(const Finding& f) {
  ++counts[static_cast<std::size_t>(f.severity)];
  for (FindingGroup& g : groups) {
    if (g.rule == f.rule && g.axis == f.axis) {
      ++g.count;
      g.last = f.at;
      return;
    }
  }
  groups.push_back({f.rule, f.severity, f.axis, 1, f.at, f.at, f.message});
}

Status locateFindings(CaptureReport& report) {
  std::vector<std::uint64_t> frames;
  for (const Finding& f : report.findings) frames.push_back(f.at.frame);
  std::sort(frames.begin(), frames.end());
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  report.frame_spans.clear();
  if (frames.empty() || report.path == "-") return {};
  auto opened = CaptureReader::open(report.path);
  if (!opened) return fail(opened.error());
  CaptureRecord record;
  auto wanted = frames.begin();
  Result<bool> more;
  // The findings' frames were all read before any damage, which the report already names.
  while (wanted != frames.end() && (more = (*opened)->next(record)) && *more) {
    if (!record.stored) return {};  // compressed: no record has a place in the file
    if (record.frame != *wanted) continue;
    report.frame_spans.emplace_back(record.frame, *record.stored);
    ++wanted;
  }
  return {};
}

std::string isoUtc(std::int64_t time_ns, int digits) {
  constexpr std::int64_t kNsPerSecond = 1000000000;
  const std::int64_t seconds =
      time_ns >= 0 ? time_ns / kNsPerSecond : -((-time_ns + kNsPerSecond - 1) / kNsPerSecond);
  const std::int64_t nanoseconds = time_ns - seconds * kNsPerSecond;
  const std::time_t whole = static_cast<std::time_t>(seconds);
  std::tm utc{};
  gmtime_r(&whole, &utc);
  std::string text = fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}", utc.tm_year + 1900,
                                 utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec);
  digits = std::clamp(digits, 0, 9);
  if (digits > 0) {
    std::int64_t fraction = nanoseconds;
    for (int d = digits; d < 9; ++d) fraction /= 10;
    text += fmt::format(".{:0{}}", fraction, digits);
  }
  return text + "Z";
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

Result<std::unique_ptr<ReportWriter>> ReportWriter::open(const std::vector<ReportTarget>& targets,
                                                         const ReportPolicy& policy) {
  std::unique_ptr<ReportWriter> writer(new ReportWriter(policy));
  for (const ReportTarget& target : targets) {
    Output output{target.format, stdout, {}, {}};
    std::error_code ec;
    const auto status = std::filesystem::status(target.path, ec);
    if (!target.path.empty() && target.path != "-" && std::filesystem::exists(status) &&
        !std::filesystem::is_regular_file(status)) {
      // A device or a pipe (/dev/null, a FIFO) is written as it is: renaming a file over it
      // would replace it.
      std::FILE* out = std::fopen(target.path.c_str(), "w");
      if (out == nullptr)
        return fail(fmt::format("{}: cannot write: {}", target.path, std::strerror(errno)));
      output = {target.format, out, target.path, {}};
    } else if (!target.path.empty() && target.path != "-") {
      // Through a link, the file it names is replaced, not the link.
      const std::filesystem::path path =
          std::filesystem::is_symlink(std::filesystem::symlink_status(target.path, ec))
              ? std::filesystem::weakly_canonical(target.path, ec)
              : std::filesystem::path(target.path);
      std::string temporary = (path.parent_path() / ("." + path.filename().string() + ".XXXXXX"))
                                  .lexically_normal()
                                  .string();
      const int fd = ::mkstemp(temporary.data());
      // mkstemp's file is private (0600); the report gets the mode a new file would have.
      const mode_t mask = ::umask(0);
      ::umask(mask);
      if (fd >= 0) ::fchmod(fd, 0666 & ~mask);
      std::FILE* out = fd >= 0 ? ::fdopen(fd, "w") : nullptr;
      if (out == nullptr) {
        if (fd >= 0) {
          ::close(fd);
          ::unlink(temporary.c_str());
        }
        return fail(fmt::format("{}: cannot write: {}", target.path, std::strerror(errno)));
      }
      output = {target.format, out, path.string(), std::move(temporary)};
    }
    writer->outputs_.push_back(std::move(output));
  }
  static std::vector<std::string> temporaries;
  temporaries.clear();
  for (const Output& o : writer->outputs_) {
    if (!o.temporary.empty()) temporaries.push_back(o.temporary);
  }
  g_temporaries = &temporaries;
  for (std::size_t i = 0; i < std::size(kInterrupts); ++i) {
    g_previous[i] = std::signal(kInterrupts[i], removeTemporaries);
    if (g_previous[i] == SIG_IGN) std::signal(kInterrupts[i], SIG_IGN);
  }
  return writer;
}

ReportWriter::~ReportWriter() {
  for (std::size_t i = 0; i < std::size(kInterrupts); ++i) {
    if (g_previous[i] != SIG_ERR) std::signal(kInterrupts[i], g_previous[i]);
  }
  g_temporaries = nullptr;
  for (const Output& o : outputs_) {
    if (o.temporary.empty()) continue;
    std::fclose(o.out);
    ::unlink(o.temporary.c_str());
  }
}

bool ReportWriter::keepsFindings() const {
  return std::any_of(outputs_.begin(), outputs_.end(),
                     [](const Output& o) { return o.format->keeps_findings; });
}

bool ReportWriter::drawsTimelines() const {
  return std::any_of(outputs_.begin(), outputs_.end(),
                     [](const Output& o) { return o.format->draws_timelines; });
}

bool ReportWriter::locatesFrames() const {
  return std::any_of(outputs_.begin(), outputs_.end(),
                     [](const Output& o) { return o.format->locates_frames; });
}

void ReportWriter::beginCapture(const CaptureReport& report) {
  for (const Output& o : outputs_) {
    if (o.format->begin_capture != nullptr) o.format->begin_capture({o.out, policy_}, report);
  }
}

void ReportWriter::finding(const CaptureReport& report, const Finding& f) {
  for (const Output& o : outputs_) {
    if (o.format->finding != nullptr) o.format->finding({o.out, policy_}, report, f);
  }
}

void ReportWriter::endCapture(const CaptureReport& report) {
  for (const Output& o : outputs_) {
    if (o.format->end_capture != nullptr) o.format->end_capture({o.out, policy_}, report);
  }
}

Status ReportWriter::finish(const std::vector<CaptureReport>& reports) {
  Status status;
  for (Output& o : outputs_) {
    if (o.format->finish != nullptr) o.format->finish({o.out, policy_}, reports);
    if (o.temporary.empty()) {
      const bool written = std::fflush(o.out) == 0;
      const bool closed = o.out == stdout || std::fclose(o.out) == 0;
      if ((!written || !closed) && status)
        status =
            fail(fmt::format("{}: cannot write: {}", o.path.empty() ? "standard output" : o.path,
                             std::strerror(errno)));
      o.out = stdout;
      continue;
    }
    const bool written = std::fflush(o.out) == 0 && ::fsync(fileno(o.out)) == 0;
    const bool closed = std::fclose(o.out) == 0;
    const std::string temporary = std::exchange(o.temporary, {});
    if (!written || !closed || std::rename(temporary.c_str(), o.path.c_str()) != 0) {
      const int error = errno;
      ::unlink(temporary.c_str());
      if (status) status = fail(fmt::format("{}: cannot write: {}", o.path, std::strerror(error)));
    }
  }
  return status;
}

}  // namespace ncservo::cli
