// `validate --format text`: findings grouped per rule and axis (each one with --verbose), each
// capture's summary, and the verdict line.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <iterator>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncservo/incidents/causes.hpp"
#include "ncservo/layout/decoder.hpp"
#include "ncservo/model/al_tracker.hpp"
#include "ncservo/model/timing_text.hpp"
#include "report_format.hpp"

namespace ncservo::report::detail {

namespace {

// Beside a NO SERVO that asks for a layout: how a --config file gives one, indented.
void writeLayoutExample(std::FILE* out) {
  fmt::print(out, "  a --config file gives each axis (docs/configuration.md#axis), e.g.:\n");
  std::string_view example = kLayoutConfigExample;
  while (!example.empty()) {
    const std::size_t end = example.find('\n');
    fmt::print(out, "    {}\n", example.substr(0, end));
    example.remove_prefix(end == std::string_view::npos ? example.size() : end + 1);
  }
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
    case Verdict::Warn:
      return "WARN";
    case Verdict::Pass:
      break;
  }
  return "PASS";
}

// The run's word: its most serious capture's, in this order; an error found before a capture's
// damage fails the run as well.
Verdict runVerdict(const Judge& judge, const std::vector<CaptureReport>& reports) {
  constexpr Verdict kOrder[] = {Verdict::Fail, Verdict::Unreadable, Verdict::NoServo, Verdict::Warn,
                                Verdict::Pass};
  std::size_t worst = std::size(kOrder) - 1;
  for (const CaptureReport& r : reports) {
    const Verdict v = r.counted(Severity::Error) > 0 ? Verdict::Fail : judge.verdict(r);
    worst = std::min<std::size_t>(
        worst, std::find(std::begin(kOrder), std::end(kOrder), v) - std::begin(kOrder));
  }
  return kOrder[worst];
}

// One line per rule and axis: how many findings, the first and last frame, the first message.
void writeTextGroups(const ReportSink& sink, const CaptureReport& r) {
  for (const FindingGroup& g : r.groups) {
    const std::string first =
        fmt::format("{} ({:.6f} s, {})", g.first.frame, seconds(r, g.first), dayTimeOf(r, g.first));
    fmt::print(sink.out, "{:<7} {:<7} {} {} finding{}{}, {}: {}\n", severityName(g.severity),
               ruleDef(g.rule).code, axisLabel(r, g.axis), g.count, g.count == 1 ? "" : "s",
               r.baseline ? fmt::format(" ({} new)", g.added) : std::string(),
               g.count == 1 ? "frame " + first
                            : fmt::format("frames {} to {} ({:.6f} s, {}), first", first,
                                          g.last.frame, seconds(r, g.last), dayTimeOf(r, g.last)),
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

// Each cyclic frame's own cycle, when there are several (one is the header's cycle).
void writeCyclicFrames(std::FILE* out, const CaptureReport& r) {
  if (r.cyclic_frames.size() < 2) return;
  std::vector<std::string> items;
  for (const CyclicFrameSummary& f : r.cyclic_frames) {
    std::vector<std::string> names;
    for (const CyclicDatagram& d : f.datagrams)
      names.push_back(fmt::format("{} 0x{:08X}", ecat::commandName(d.command), d.address));
    items.push_back(fmt::format(
        "{} every {}, {} cycles", fmt::join(names, "+"),
        f.cycle_ns ? fmt::format("{:.1f} us", static_cast<double>(*f.cycle_ns) / 1000.0) : "?",
        f.cycles));
  }
  fmt::print(out, "cyclic frames: {}\n", fmt::join(items, "; "));
}

// A link type as Wireshark's capture file properties name it.
std::string linkTypeText(int link_type) {
  switch (link_type) {
    case 1:
      return "Ethernet";
    case 113:
      return "Linux cooked";
    case 276:
      return "Linux cooked v2";
    default:
      return fmt::format("link type {}", link_type);
  }
}

// What each interface held, when the records came from more than one (docs/cli.md#interfaces).
void writeInterfaces(std::FILE* out, const CaptureReport& r) {
  if (r.interfaces.size() + (r.interface_records_omitted > 0 ? 1 : 0) < 2) return;
  std::vector<std::string> items;
  for (const CaptureInterface& i : r.interfaces) {
    items.push_back(fmt::format("{}: {}, {} frame{}{}", i.id, linkTypeText(i.link_type), i.frames,
                                i.frames == 1 ? "" : "s", i.ethercat ? ", EtherCAT" : ""));
  }
  if (r.interface_records_omitted > 0) {
    items.push_back(fmt::format("{} frames of further interfaces", r.interface_records_omitted));
  }
  fmt::print(out, "interfaces: {} ({})\n", r.interfaces.size(), fmt::join(items, "; "));
}

// Copies the capture missed, told apart from cycles the bus lost (docs/timing.md "Capture loss").
void writeCaptureLoss(std::FILE* out, const CaptureReport& r) {
  if (const std::string missing =
          copiesMissingText(r.master_copies_missing, r.returned_copies_missing);
      !missing.empty()) {
    fmt::print(out, "copies missing: {}\n", missing);
  }
  if (r.capture_drops && r.capture_drops->dropped() > 0) {
    fmt::print(out, "capture drops: {}\n", describeCaptureDrops(*r.capture_drops));
  }
}

// Each axis: where it was found (station, its PDOs' logical or SM addresses, the inference's
// evidence), then its final state and error history.
void writeTextAxes(std::FILE* out, const CaptureReport& r) {
  for (std::size_t i = 0; i < r.layout.size(); ++i) {
    const AxisInfo& info = r.layout[i];
    fmt::print(out, "  {}:", info.name);
    if (info.has_station) fmt::print(out, " station 0x{:04X},", info.station);
    if (info.logical) {
      fmt::print(out, " outputs 0x{:08X}, inputs 0x{:08X}\n", info.outputs, info.inputs);
    } else {
      fmt::print(out, " SM2 0x{:08X}, SM3 0x{:08X}\n", info.sm_outputs, info.sm_inputs);
    }
    if (i < r.inferred.size()) fmt::print(out, "    {}\n", describeInference(r.inferred[i]));
  }
  for (const AxisSummary& a : r.axes) {
    fmt::print(out, "  {} (axis {}): {}; telegram failures {}", a.name, a.index,
               a.state ? driveStateName(*a.state) : "no inputs seen", a.telegram_failures);
    if (a.ready_mode) fmt::print(out, "; Servo_Ready_Mode {}", *a.ready_mode);
    fmt::print(out, "\n");
    for (const ErrorHistoryEntry& e : a.error_history) {
      fmt::print(out, "    error {} (0x{:04X}) at frame {}, {:.6f} s ({})\n",
                 sewCauseText(*e.cause), e.cause->canopen, e.at.frame, seconds(r, e.at),
                 dayTimeOf(r, e.at));
    }
    // docs/drive-messages.md: what the drive itself said, beside the history kept from SEW.
    for (const DriveMessage& m : r.drive_messages) {
      if (!slaveOfAxis(r, a.index, m.slave)) continue;
      fmt::print(out, "    drive said: {} at frame {}", describeDriveMessage(m), m.frame);
      if (m.request_frame) fmt::print(out, " (request frame {})", *m.request_frame);
      fmt::print(out, "\n");
    }
  }
}

// docs/drive-messages.md: the links the ESCs' counters name, the counters' rises, the mailbox's
// notes, and the drive messages of slaves that are no axis.
void writeBusDiagnosis(std::FILE* out, const CaptureReport& r) {
  for (const LinkFault& f : r.link_faults) {
    fmt::print(out, "link fault: {}: {} errors at frame {}\n", linkFaultText(f), f.errors, f.frame);
  }
  if (!r.esc_errors.empty()) {
    std::uint64_t total = 0;
    for (const EscErrorDelta& d : r.esc_errors) total += d.delta;
    fmt::print(out, "ESC error counters: {} rises ({} counts){}\n", r.esc_errors.size(), total,
               r.esc_errors_omitted > 0 ? fmt::format(", {} more not listed", r.esc_errors_omitted)
                                        : std::string());
  }
  for (const MailboxNote& n : r.mailbox_notes) {
    fmt::print(out, "mailbox: {} at frame {}: {}\n", slaveName(n.slave), n.frame, n.text);
  }
  for (const DriveMessage& m : r.drive_messages) {
    if (slaveIsAxis(r, m.slave)) continue;
    fmt::print(out, "{} said: {} at frame {}\n", slaveName(m.slave), describeDriveMessage(m),
               m.frame);
  }
}

// The rules that judged nothing, in one line: the rules of each axis (or the bus), axes with the
// same rules named together.
void writeNotJudged(std::FILE* out, const CaptureReport& r) {
  if (r.coverage.not_judged.empty()) return;
  std::vector<std::pair<std::string, std::vector<std::string>>> groups;  // rules, axes
  std::optional<std::uint16_t> current;
  std::vector<std::string> codes;
  const auto close = [&] {
    if (codes.empty()) return;
    const std::string rules = fmt::format("{}", fmt::join(codes, ", "));
    const std::string who = current ? axisName(r, *current) : std::string("bus");
    auto same =
        std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == rules; });
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

}  // namespace

std::string incidentSummary(const CaptureReport& r, const Incident& incident) {
  return fmt::format("{} at frame {}, {:.3f} s ({}) \u2014 {}: {}",
                     incidentHeadline(incident, axisLabel(r, incident.axis)), incident.at.frame,
                     seconds(r, incident.at), dayTimeOf(r, incident.at),
                     causeDef(incident.cause).name, incident.cause_text);
}

std::string incidentDetails(const Incident& incident, std::string_view indent) {
  std::string text;
  if (!incident.evidence.empty()) {
    std::vector<std::string> items;
    for (const IncidentEvidence& e : incident.evidence)
      items.push_back(fmt::format("frame {} {}", e.at.frame, e.what));
    text += fmt::format("{}evidence: {}\n", indent, fmt::join(items, "; "));
  }
  std::vector<std::string> recovery;
  if (incident.error_clear)
    recovery.push_back(fmt::format("errors cleared at frame {}", incident.error_clear->frame));
  if (incident.reenabled) {
    recovery.push_back(fmt::format("{} at frame {}",
                                   incident.kind == IncidentKind::Esm         ? "back in OP"
                                   : incident.kind == IncidentKind::BusOutage ? "cycles run again"
                                                                              : "enabled again",
                                   incident.reenabled->frame));
  }
  text +=
      fmt::format("{}recovery: {}\n", indent,
                  !recovery.empty() ? fmt::format("{}", fmt::join(recovery, ", "))
                  : incident.ended
                      ? fmt::format("none before the next fault (frame {})", incident.end.frame)
                      : fmt::format("none before the capture ends (frame {})", incident.end.frame));
  return text;
}

// docs/incidents.md#the-text-report: per axis (then the bus and slaves that are no axis), each
// incident's line with its cause (and, against a baseline, whether it is new), its evidence and
// its recovery.
void writeTextIncidents(std::FILE* out, const CaptureReport& r) {
  if (r.incidents.empty()) return;
  fmt::print(out, "incidents: {}{}\n", r.incidents.size(),
             r.incidents_omitted > 0 ? fmt::format(" ({} more not kept)", r.incidents_omitted)
                                     : std::string());
  std::vector<std::optional<std::uint16_t>> groups;
  for (const Incident& incident : r.incidents) {
    if (std::find(groups.begin(), groups.end(), incident.axis) == groups.end())
      groups.push_back(incident.axis);
  }
  std::sort(groups.begin(), groups.end(), [](const auto& a, const auto& b) {
    return a && b ? *a < *b : a.has_value();  // the bus last
  });
  for (const std::optional<std::uint16_t>& group : groups) {
    fmt::print(out, "  {}:\n", axisLabel(r, group));
    for (std::size_t n = 0; n < r.incidents.size(); ++n) {
      const Incident& incident = r.incidents[n];
      if (incident.axis != group) continue;
      const std::string state = n < r.incident_states.size()
                                    ? fmt::format(" [{}]", baselineStateName(r.incident_states[n]))
                                    : std::string();
      fmt::print(out, "    incident {}{}: {}\n{}", n + 1, state, incidentSummary(r, incident),
                 incidentDetails(incident, "      "));
    }
  }
  for (const ReportedIncident& i : r.baseline_absent_incidents) {
    fmt::print(out, "  absent from the baseline's incidents: {} (frame {})\n",
               fingerprintText(i.fingerprint), i.frame);
  }
}

void writeTextHeading(const ReportSink& sink, const CaptureReport& r) {
  fmt::print(sink.out, "== {}\n", r.path);
}

void writeTextFinding(const ReportSink& sink, const CaptureReport& r, const Finding& f,
                      BaselineState state) {
  if (!sink.options.verbose) return;
  // One buffer, no temporary strings: a storm of findings writes thousands of these lines a
  // second, and the monitor must keep up with the bus meanwhile (docs/benchmarks.md).
  fmt::memory_buffer line;
  auto out = std::back_inserter(line);
  fmt::format_to(out, "{:<7} {:<7} {} frame {} (", severityName(f.severity), ruleDef(f.rule).code,
                 axisLabel(r, f.axis), f.at.frame);
  char time[kSecondsTextSize];
  line.append(time, writeSeconds(f.at.time_ns - r.first_time_ns, time));
  line.append(std::string_view(" s, "));
  char day_time[kTimeOfDaySize];
  line.append(day_time, writeTimeOfDay(f.at.time_ns, r.zone, day_time));
  line.push_back(')');
  if (f.since.frame != f.at.frame) fmt::format_to(out, ", since frame {}", f.since.frame);
  fmt::format_to(out, ": {}", f.message);
  if (state != BaselineState::None) fmt::format_to(out, " [{}]", baselineStateName(state));
  line.push_back('\n');
  std::fwrite(line.data(), 1, line.size(), sink.out);
}

namespace {

// Against a baseline (docs/baselines.md): its findings not seen again, then the counts.
void writeTextBaseline(std::FILE* out, const CaptureReport& r) {
  if (!r.baseline) return;
  for (const ReportedFinding& f : r.baseline_absent) {
    fmt::print(out, "absent  {} (baseline frame {}): {}\n", fingerprintText(f.fingerprint), f.frame,
               f.message);
  }
  const ReportedCapture* matched = r.baseline->capture();
  fmt::print(out, "baseline: {} against {}{}\n", describeBaseline(r), r.baseline_path,
             matched != nullptr ? fmt::format(" ({})", matched->path)
                                : std::string(" (no capture of this name in it)"));
}

// "2 errors, 1 warning, 0 info", of the findings that count; with a baseline "2 new errors, …".
std::string countedText(const std::array<std::size_t, 3>& counts, bool baseline) {
  const char* adjective = baseline ? "new " : "";
  return fmt::format("{} {}error{}, {} {}warning{}, {} {}info", counts[2], adjective,
                     counts[2] == 1 ? "" : "s", counts[1], adjective, counts[1] == 1 ? "" : "s",
                     counts[0], adjective);
}

}  // namespace

void writeTextSummary(const ReportSink& sink, const CaptureReport& r) {
  std::FILE* out = sink.out;
  // Nothing was read: its verdict and why, nothing else (no frames, no layout to speak of).
  if (r.unopened()) {
    fmt::print(out, "capture verdict: UNREADABLE - {}\n", *r.error);
    return;
  }
  // Before the findings: a layout that does not fit explains them.
  for (const std::string& warning : r.layout_warnings) {
    fmt::print(out, "warning: layout does not fit: {}\n", warning);
  }
  if (!sink.options.verbose) writeTextGroups(sink, r);
  fmt::print(out, "{}: {} frames, {} cycles", r.path, r.frames, r.cycles);
  if (r.cycle_time.median_us) {
    fmt::print(out, ", cycle {:.1f} us (p99 {:.1f}, max {:.1f})", *r.cycle_time.median_us,
               r.cycle_time.p99_us.value_or(0), r.cycle_time.max_us.value_or(0));
  }
  fmt::print(out, "\n");
  if (r.frames > 0) {
    fmt::print(out, "start: {} (times of day in {})\n", startOf(r),
               r.zone == TimeZone::Utc ? "UTC" : "local time");
  }
  if (r.scope.limited()) {
    fmt::print(out, "scope: {} (the rest neither reported nor counted)\n", describeScope(r.scope));
  }
  writeInterfaces(out, r);
  fmt::print(out, "layout: {}, {} ax{}\n", layoutSourceName(r.layout_source), r.layout.size(),
             r.layout.size() == 1 ? "is" : "es");
  if (r.startup_frames_cut > 0) {
    fmt::print(out, "  {}\n", describeStartupCut(r.startup_frames_cut));
  }
  if (r.late_layout.certain_at > 0) fmt::print(out, "  {}\n", describeLateLayout(r.late_layout));
  writeTextAxes(out, r);
  writeTextIncidents(out, r);
  fmt::print(out, "timestamps: {}\n", timestampSourceName(r.timestamps));
  fmt::print(out, "clock: {}\n", describeClock(r.clock));
  if (r.duplicates.count > 0) {
    fmt::print(out, "duplicates: {} records ignored (the first: frame {})\n", r.duplicates.count,
               r.duplicates.first_frame);
  }
  const bool own_stamps =
      r.clock.source == ClockSource::Capture || r.clock.source == ClockSource::Probe;
  std::fputs(
      timingText(r.timing,
                 own_stamps ? timestampSourceName(r.timestamps) : clockSourceName(r.clock.source),
                 own_stamps ? timestampResolutionNs(r.timestamps, r.timestamp_digits) : 1)
          .c_str(),
      out);
  fmt::print(out, "{}\n", describeCyclicDatagrams(r));
  writeCyclicFrames(out, r);
  writeCaptureLoss(out, r);
  std::fputs(dcText(r.dc, r.dc_settled_ns, clockSourceMeaning(r.clock.source)).c_str(), out);
  writeBusDiagnosis(out, r);
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
  writeNotJudged(out, r);
  if (!r.coverage.complete()) fmt::print(out, "NO SERVO: {}\n", r.coverage.reason);
  if (!r.coverage.complete() && r.coverage.wants_layout) writeLayoutExample(out);
  if (r.error) fmt::print(out, "error: {}\n", *r.error);
  writeTextBaseline(out, r);
  const std::string dropped =
      r.capture_drops && r.capture_drops->dropped() > 0
          ? fmt::format("; the capture dropped {} frames", r.capture_drops->dropped())
          : std::string();
  fmt::print(out, "capture verdict: {} - {} ({}{})\n", verdictHeadline(sink.judge.verdict(r)),
             countedText(r.baseline ? r.new_counts : r.counts, r.baseline.has_value()), r.path,
             dropped);
}

void writeTextVerdict(const ReportSink& sink, const std::vector<CaptureReport>& reports) {
  std::array<std::size_t, 3> counts{};
  std::size_t added = 0, unchanged = 0, absent = 0;  // against a baseline
  const bool baseline = !reports.empty() && reports.front().baseline.has_value();
  std::size_t unopened = 0;   // captures of which nothing could be read
  std::size_t unread = 0;     // captures read in part: not to their end
  std::size_t unchecked = 0;  // captures read where not every axis was checked
  for (const CaptureReport& r : reports) {
    for (std::size_t s = 0; s < 3; ++s) counts[s] += r.counted(static_cast<Severity>(s));
    added += r.newCount();
    unchanged += r.unchanged;
    absent += r.baseline_absent.size();
    unopened += r.unopened() ? 1 : 0;
    unread += r.error && !r.unopened() ? 1 : 0;
    unchecked += r.unopened() || r.coverage.complete() ? 0 : 1;
  }
  std::string notes;
  if (unopened > 0) notes += fmt::format(", {} unreadable", unopened);
  if (unread > 0) notes += fmt::format(", {} not read to the end", unread);
  if (unchecked > 0) notes += fmt::format(", {} with no servo checked", unchecked);
  // docs/baselines.md: with a baseline the words and counts are about the new findings.
  if (baseline) {
    notes += fmt::format(", against the baseline: {} new, {} unchanged, {} absent", added,
                         unchanged, absent);
  }
  const RunStatus status = sink.judge.runStatus(reports);
  const bool interrupted = status.interrupted;
  const std::string& reason = status.reason;
  // docs/cli.md#verdicts: the word describes the captures; the exit status and why close the line.
  fmt::print(sink.out, "verdict: {} - {} in {} capture{}{}{} (exit {}{}{})\n",
             interrupted ? "INTERRUPTED" : verdictHeadline(runVerdict(sink.judge, reports)),
             countedText(counts, baseline), reports.size(), reports.size() == 1 ? "" : "s",
             interrupted ? " finished" : "", notes, status.exit_status, reason.empty() ? "" : ": ",
             reason);
}

}  // namespace ncservo::report::detail

namespace ncservo::report {

using detail::incidentDetails;
using detail::incidentRuleId;
using detail::incidentSummary;

std::string incidentComment(const CaptureReport& report, const Incident& incident) {
  std::string comment =
      fmt::format("{} {}", incidentRuleId(incident.cause), incidentSummary(report, incident));
  // The details' lines, one after another.
  const std::string lines = incidentDetails(incident, "");
  std::string_view details = lines;
  while (!details.empty()) {
    const std::size_t end = std::min(details.find('\n'), details.size());
    comment += fmt::format("; {}", details.substr(0, end));
    details.remove_prefix(std::min(end + 1, details.size()));
  }
  return comment;
}

bool isIncidentComment(std::string_view comment) {
  constexpr std::string_view kPrefix = "INC-";
  if (comment.substr(0, kPrefix.size()) != kPrefix) return false;
  const std::size_t space = comment.find(' ');
  return space != std::string_view::npos &&
         findCause(comment.substr(kPrefix.size(), space - kPrefix.size())).has_value();
}

}  // namespace ncservo::report
