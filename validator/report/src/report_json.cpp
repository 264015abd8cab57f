// `validate --format json`: one document for all captures; its parts are JSON Lines' too.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "ncservo/incidents/causes.hpp"
#include "ncservo/wire/diagnosis_texts.hpp"
#include "report_format.hpp"

namespace ncservo::report::detail {

namespace {

std::string hex16(std::uint16_t v) {
  return fmt::format("0x{:04X}", v);
}
std::string hex32(std::uint32_t v) {
  return fmt::format("0x{:08X}", v);
}

Json optionalNumber(const std::optional<double>& v) {
  return v ? Json(*v) : Json(nullptr);
}

// What the ESL probe headers said (docs/protocol.md §8), when there were any.
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
          {"histogram_zero", us(s.reference_ns)},
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

// Each cyclic frame with its own cycle (docs/timing.md "Which frames").
Json cyclicFramesJson(const CaptureReport& r) {
  Json list = Json::array();
  for (const CyclicFrameSummary& f : r.cyclic_frames) {
    Json datagrams = Json::array();
    for (const CyclicDatagram& d : f.datagrams) {
      datagrams.push_back({{"command", ecat::commandName(d.command)},
                           {"address", hex32(d.address)},
                           {"length", d.length}});
    }
    list.push_back({{"datagrams", std::move(datagrams)},
                    {"frames", f.datagrams.empty() ? 0 : f.datagrams.front().frames},
                    {"cycles", f.cycles},
                    {"cycle_us", f.cycle_ns ? Json(microseconds(static_cast<double>(*f.cycle_ns)))
                                            : Json(nullptr)}});
  }
  return list;
}

// `timing.dc` (docs/timing.md): one entry per slave whose distributed clock was read.
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
                    {"drift_uncertainty_ppm", ppm(s.drift_uncertainty_ppm)},
                    {"drift_first_half_ppm", ppm(s.first_half_ppm)},
                    {"drift_second_half_ppm", ppm(s.second_half_ppm)},
                    {"systime_diff_ns", std::move(difference)},
                    {"settled_frame", s.settled_frame ? Json(*s.settled_frame) : Json(nullptr)}});
  }
  return list;
}

}  // namespace

Json findingJson(const CaptureReport& r, const Finding& f, BaselineState state) {
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
  j["fingerprint"] = fingerprintText(r.fingerprintOf(f));  // docs/baselines.md#fingerprints
  if (state != BaselineState::None) j["baseline"] = baselineStateName(state);
  return j;
}

Json reportedFindingJson(const ReportedFinding& f, const char* state) {
  return {{"rule", f.fingerprint.rule},
          {"slug", f.slug},
          {"severity", severityName(f.severity)},
          {"axis", f.axis ? Json(*f.axis) : Json(nullptr)},
          {"axis_name", f.fingerprint.axis ? Json(*f.fingerprint.axis) : Json(nullptr)},
          {"frame", f.frame},
          {"since_frame", f.since_frame},
          {"time", f.time},
          {"message", f.message},
          {"fingerprint", fingerprintText(f.fingerprint)},
          {"baseline", state}};
}

Json baselineJson(const CaptureReport& r) {
  const ReportedCapture* matched = r.baseline->capture();
  return {
      {"report", r.baseline_path},
      {"capture", matched != nullptr ? Json(matched->path) : Json(nullptr)},
      {"new", r.newCount()},
      {"unchanged", r.unchanged},
      {"absent", r.baseline_absent.size()},
      {"new_summary",
       {{"error", r.new_counts[2]}, {"warning", r.new_counts[1]}, {"info", r.new_counts[0]}}},
      {"incidents",
       {{"new", std::count(r.incident_states.begin(), r.incident_states.end(), BaselineState::New)},
        {"unchanged",
         std::count(r.incident_states.begin(), r.incident_states.end(), BaselineState::Unchanged)},
        {"absent", r.baseline_absent_incidents.size()}}}};
}

Json incidentJson(const CaptureReport& r, std::size_t index) {
  const Incident& incident = r.incidents[index];
  Json j;
  j["kind"] = incidentKindName(incident.kind);
  j["axis"] = incident.axis ? Json(*incident.axis) : Json(nullptr);
  j["axis_name"] = incident.axis ? Json(axisName(r, *incident.axis)) : Json(nullptr);
  if (incident.kind == IncidentKind::Esm) {
    j["station"] = incident.station ? Json(hex16(*incident.station)) : Json(nullptr);
  }
  j["frame"] = incident.at.frame;
  j["time"] = seconds(r, incident.at);
  j["time_utc"] = utcOf(r, incident.at);
  j["end_frame"] = incident.end.frame;
  Json errors = Json::array();
  for (const SewCause* cause : incident.errors) {
    errors.push_back({{"bit", sewBitName(*cause)},
                      {"code", cause->display},
                      {"canopen", hex16(cause->canopen)}});
  }
  j["errors"] = std::move(errors);
  j["cause"] = {{"id", causeDef(incident.cause).name}, {"text", incident.cause_text}};
  j["fingerprint"] = fingerprintText(r.fingerprintOf(incident));
  if (index < r.incident_states.size()) j["baseline"] = baselineStateName(r.incident_states[index]);
  Json evidence = Json::array();
  for (const IncidentEvidence& e : incident.evidence) {
    evidence.push_back({{"frame", e.at.frame}, {"what", e.what}});
  }
  j["evidence"] = std::move(evidence);
  Json before = Json::object();
  Json before_frames = Json::object();
  for (std::size_t i = 0; i < kBefore.size(); ++i) {
    if (!incident.before[i]) continue;
    // To the thousandth: message data is a float32.
    before[kBefore[i].key] = std::round(*incident.before[i] * 1000) / 1000;
    before_frames[kBefore[i].key] = incident.before_at[i].frame;
  }
  j["before"] = std::move(before);
  // Where each came: message codes take turns, so a value may be several cycles old.
  j["before_frames"] = std::move(before_frames);
  auto frameOf = [](const std::optional<Stamp>& at) {
    return at ? Json(at->frame) : Json(nullptr);
  };
  j["recovery"] = {{"error_clear_frame", frameOf(incident.error_clear)},
                   {"reenabled_frame", frameOf(incident.reenabled)}};
  return j;
}

// The baseline's incidents not seen again, as `diff` reads them back.
Json baselineAbsentIncidentsJson(const CaptureReport& r) {
  Json absent = Json::array();
  for (const ReportedIncident& i : r.baseline_absent_incidents) {
    const IncidentFingerprint& f = i.fingerprint;
    absent.push_back({{"kind", f.kind},
                      {"axis_name", f.axis ? Json(*f.axis) : Json(nullptr)},
                      {"cause", {{"id", f.cause}, {"text", i.text}}},
                      {"frame", i.frame},
                      {"fingerprint", fingerprintText(f)},
                      {"baseline", "absent"}});
  }
  return absent;
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

// The capture's segments (docs/timing.md#rule-time), times in the capture's own seconds.
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

// `timing` (docs/timing.md, docs/cli.md).
namespace {

// How an inferred axis was found (docs/layout.md): a confidence in percent, the handshake
// cycles seen, and whether the structure alone decided.
Json inferredJson(const AxisEvidence& e) {
  return {{"confidence", static_cast<int>(std::lround(100 * e.confidence))},
          {"handshakes_seen", e.handshakes_seen},
          {"structure_only", e.structure_only},
          {"paired_by_order", e.paired_by_order}};
}

}  // namespace

// Which clock judged the capture and why (docs/timing.md#the-clock).
Json clockJson(const CaptureReport& r) {
  const CaptureStamps& stamps = r.clock.stamps;
  const auto us = [](const std::optional<std::int64_t>& ns) {
    return ns ? Json(static_cast<double>(*ns) / 1000.0) : Json(nullptr);
  };
  Json clock{{"source", clockSourceName(r.clock.source)},
             {"why", r.clock.why},
             {"capture_stamps",
              {{"intervals", stamps.intervals},
               {"quantum_us", us(stamps.quantum_ns)},
               {"bunched", stamps.bunched},
               {"burst_us", us(stamps.burst_ns)},
               {"late_us_p99", us(stamps.late_p99_ns)}}}};
  if (r.clock.reference) clock["reference"] = hex16(r.clock.reference->adp);
  if (r.clock.source == ClockSource::Cycles) clock["cycle_us"] = r.clock.cycle_ns / 1000.0;
  if (r.untimed_frames > 0) clock["untimed_frames"] = r.untimed_frames;
  return clock;
}

Json timingJson(const CaptureReport& r) {
  Json timing{
      {"timestamps", timestampSourceName(r.timestamps)},
      {"resolution_ns", timestampResolutionNs(r.timestamps, r.timestamp_digits)},
      {"cycle_us", seriesJson(r.timing.cycle)},
      {"latency_us", seriesJson(r.timing.latency)},
      {"worst_cycles", worstJson(r.timing.worst_cycles, "since_frame", "interval_us")},
      {"worst_latencies", worstJson(r.timing.worst_latencies, "master_frame", "latency_us")},
      {"segments", segmentsJson(r)},
      {"cyclic_datagrams", cyclicDatagramsJson(r)},
      {"cyclic_frames", cyclicFramesJson(r)},
      {"master_copies_missing", r.master_copies_missing},
      {"returned_copies_missing", r.returned_copies_missing},
      {"lost_cycles", r.lost_cycles},
      {"wkc_errors", r.wkc_errors}};
  if (r.unfollowed_frames > 0) timing["frames_not_followed"] = r.unfollowed_frames;
  if (r.segment_count > r.segments.size())
    timing["segments_omitted"] = r.segment_count - r.segments.size();
  timing["dc"] = dcJson(r);
  return timing;
}

namespace {

// What the capture file says it dropped (docs/timing.md "Capture loss").
Json captureDroppedJson(const CaptureDrops& d) {
  return {{"frames", d.dropped()},
          {"interface", d.interface_dropped ? Json(*d.interface_dropped) : Json(nullptr)},
          {"system", d.system_dropped ? Json(*d.system_dropped) : Json(nullptr)}};
}

// What each interface held (docs/cli.md#interfaces).
Json interfacesJson(const CaptureReport& r) {
  Json interfaces = Json::array();
  for (const CaptureInterface& i : r.interfaces) {
    interfaces.push_back(
        {{"id", i.id}, {"link_type", i.link_type}, {"frames", i.frames}, {"ethercat", i.ethercat}});
  }
  return interfaces;
}

Json layoutAxesJson(const CaptureReport& r) {
  Json layout_axes = Json::array();
  for (std::size_t i = 0; i < r.layout.size(); ++i) {
    const AxisInfo& info = r.layout[i];
    Json a{{"index", info.index}, {"name", info.name}};
    if (info.has_station) a["station"] = hex16(info.station);
    a["outputs"] = hex32(info.logical ? info.outputs : info.sm_outputs);
    a["inputs"] = hex32(info.logical ? info.inputs : info.sm_inputs);
    if (i < r.inferred.size()) a["inferred"] = inferredJson(r.inferred[i]);
    layout_axes.push_back(std::move(a));
  }
  return layout_axes;
}

// Where the axes are and where that came from (docs/layout.md).
Json layoutJson(const CaptureReport& r) {
  Json layout{{"source", layoutSourceName(r.layout_source)}, {"axes", layoutAxesJson(r)}};
  if (r.startup_frames_cut > 0) layout["startup_frames_cut"] = r.startup_frames_cut;
  if (!r.layout_warnings.empty()) layout["warnings"] = r.layout_warnings;
  if (r.late_layout.any()) {
    const LateLayout& late = r.late_layout;
    layout["inference_windows"] = late.windows;
    layout["inference_cycles"] = late.cycles;
    if (late.certain_at > 0) {
      layout["certain_at_frame"] = late.certain_at;
      // docs/layout.md#keep-looking: forgotten while the layout was not yet certain.
      layout["unjudged_before_certain"] = {{"frames", late.unjudged_frames},
                                           {"first_frame", late.first_unjudged},
                                           {"last_frame", late.last_unjudged}};
    }
  }
  return layout;
}

Json findingsJson(const CaptureReport& r) {
  Json findings = Json::array();
  for (std::size_t i = 0; i < r.findings.size(); ++i) {
    findings.push_back(
        findingJson(r, r.findings[i],
                    i < r.baseline_states.size() ? r.baseline_states[i] : BaselineState::None));
  }
  return findings;
}

Json baselineAbsentJson(const CaptureReport& r) {
  Json absent = Json::array();
  for (const ReportedFinding& f : r.baseline_absent)
    absent.push_back(reportedFindingJson(f, "absent"));
  return absent;
}

// The axis whose slave a station is, in the layout; none for a slave that is not a servo.
const AxisInfo* axisOfSlave(const CaptureReport& r, const SlaveRef& slave) {
  if (!slave.station) return nullptr;
  for (const AxisInfo& info : r.layout) {
    if (info.has_station && info.station == *slave.station) return &info;
  }
  return nullptr;
}

}  // namespace

bool slaveOfAxis(const CaptureReport& r, std::uint16_t axis, const SlaveRef& slave) {
  if (!slave.station) return false;
  return std::any_of(r.layout.begin(), r.layout.end(), [&](const AxisInfo& info) {
    return info.index == axis && info.has_station && info.station == *slave.station;
  });
}

bool slaveIsAxis(const CaptureReport& r, const SlaveRef& slave) {
  return axisOfSlave(r, slave) != nullptr;
}

namespace {

void putSlave(Json& j, const CaptureReport& r, const SlaveRef& slave) {
  j["station"] = slave.station ? Json(*slave.station) : Json(nullptr);
  if (!slave.station && slave.position) j["position"] = *slave.position;
  const AxisInfo* axis = axisOfSlave(r, slave);
  j["axis"] = axis ? Json(axis->index) : Json(nullptr);
  j["axis_name"] = axis ? Json(axis->name) : Json(nullptr);
}

std::string hexBytes(const std::uint8_t* bytes, std::size_t count) {
  std::string out;
  for (std::size_t i = 0; i < count; ++i) out += fmt::format("{:02x}", bytes[i]);
  return out;
}

Json textOrNull(const char* text) {
  return text ? Json(text) : Json(nullptr);
}

}  // namespace

Json driveMessageJson(const CaptureReport& r, const DriveMessage& m) {
  Json j{{"frame", m.frame}};
  if (m.request_frame) j["request_frame"] = *m.request_frame;
  putSlave(j, r, m.slave);
  j["kind"] = driveMessageKindName(m.kind);
  switch (m.kind) {
    case DriveMessage::Kind::Emergency:
      j["code"] = m.emergency.code;
      j["register"] = m.emergency.error_register;
      j["data"] = hexBytes(m.emergency.data.data(), m.emergency.data.size());
      j["text"] = textOrNull(diag::errorCodeText(m.emergency.code));
      break;
    case DriveMessage::Kind::SdoAbort:
      j["index"] = m.index;
      j["subindex"] = m.subindex;
      j["abort"] = m.abort_code;
      j["text"] = textOrNull(diag::abortText(m.abort_code));
      break;
    case DriveMessage::Kind::SdoUpload:
    case DriveMessage::Kind::SdoDownload:
      j["index"] = m.index;
      j["subindex"] = m.subindex;
      j["value"] = m.value ? Json(*m.value) : Json(nullptr);
      if (!m.value) j["size"] = m.size;
      if (const char* object = diag::objectName(m.index)) j["object"] = object;
      if (const std::optional<diag::ErrorFieldEntry> e = errorHistoryEntry(m)) {
        j["entry"] = {{"number", e->number},
                      {"class", e->error_class},
                      {"code", e->code},
                      {"text", textOrNull(diag::errorCodeText(e->code))}};
      }
      break;
  }
  return j;
}

Json escErrorJson(const CaptureReport& r, const EscErrorDelta& d) {
  (void)r;
  Json j{{"station", d.slave.station ? Json(*d.slave.station) : Json(nullptr)}};
  if (!d.slave.station && d.slave.position) j["position"] = *d.slave.position;
  if (d.broadcast) j["broadcast"] = true;
  j["port"] = d.port;
  j["counter"] = diag::escCounterName(d.counter);
  j["delta"] = d.delta;
  j["frame"] = d.frame;
  return j;
}

Json linkFaultJson(const LinkFault& f) {
  auto side = [](const std::optional<SlaveRef>& slave, std::uint8_t port) -> Json {
    if (!slave) return nullptr;
    Json j{{"station", slave->station ? Json(*slave->station) : Json(nullptr)}, {"port", port}};
    if (!slave->station && slave->position) j["position"] = *slave->position;
    return j;
  };
  return {{"upstream", side(f.upstream, f.upstream_port)},
          {"downstream", side(f.downstream, f.downstream_port)},
          {"errors", f.errors},
          {"frame", f.frame},
          {"text", linkFaultText(f)}};
}

namespace {

Json incidentsJson(const CaptureReport& r) {
  Json incidents = Json::array();
  for (std::size_t i = 0; i < r.incidents.size(); ++i) incidents.push_back(incidentJson(r, i));
  return incidents;
}

Json stateTimelineJson(const CaptureReport& r, const AxisSummary& a) {
  Json timeline = Json::array();
  for (const StateChange& s : a.timeline) {
    timeline.push_back({{"state", driveStateName(s.state)},
                        {"transition", s.transition ? Json(s.transition) : Json(nullptr)},
                        {"frame", s.at.frame},
                        {"time", seconds(r, s.at)},
                        {"time_utc", utcOf(r, s.at)}});
  }
  return timeline;
}

Json errorHistoryJson(const CaptureReport& r, const AxisSummary& a) {
  Json history = Json::array();
  for (const ErrorHistoryEntry& e : a.error_history) {
    history.push_back({{"code", e.cause->display},
                       {"name", sewCauseName(*e.cause)},
                       {"canopen", hex16(e.cause->canopen)},
                       {"frame", e.at.frame},
                       {"time", seconds(r, e.at)},
                       {"time_utc", utcOf(r, e.at)}});
  }
  return history;
}

// Each axis at the end of the capture: its state, how it got there, its errors and failures.
Json axesJson(const CaptureReport& r) {
  Json axes = Json::array();
  for (const AxisSummary& a : r.axes) {
    Json axis{{"index", a.index},
              {"name", a.name},
              {"state", a.state ? Json(driveStateName(*a.state)) : Json(nullptr)},
              {"state_timeline", stateTimelineJson(r, a)}};
    if (a.timeline_omitted > 0) axis["state_timeline_omitted"] = a.timeline_omitted;
    axis["error_history"] = errorHistoryJson(r, a);
    axis["telegram_failures"] = a.telegram_failures;
    axis["servo_ready_mode"] = a.ready_mode ? Json(*a.ready_mode) : Json(nullptr);
    axes.push_back(std::move(axis));
  }
  return axes;
}

// Nothing was read (docs/cli.md#verdicts): the verdict and why, with the empty parts a reader of
// every capture expects, and no layout, timing or axes to speak of.
void addUnopened(Json& c, const CaptureReport& r) {
  c["reason"] = *r.error;
  c["frames"] = 0;
  c["findings"] = Json::array();
  c["summary"] = {{"error", 0}, {"warning", 0}, {"info", 0}};
  c["error"] = *r.error;
}

}  // namespace

Json captureJson(const CaptureReport& r, Verdict verdict) {
  Json c;
  c["path"] = r.path;
  c["verdict"] = verdictName(verdict);
  if (r.unopened()) {
    addUnopened(c, r);
    return c;
  }
  if (!r.coverage.complete()) c["reason"] = r.coverage.reason;
  if (!r.coverage.missing.empty()) c["missing_axes"] = r.coverage.missing;
  if (r.scope.limited()) c["scope"] = describeScope(r.scope);
  c["frames"] = r.frames;
  c["cycles"] = r.cycles;
  c["cycle_time_us"] = {{"median", optionalNumber(r.cycle_time.median_us)},
                        {"p99", optionalNumber(r.cycle_time.p99_us)},
                        {"max", optionalNumber(r.cycle_time.max_us)}};
  if (r.capture_drops) c["capture_dropped"] = captureDroppedJson(*r.capture_drops);
  c["interfaces"] = interfacesJson(r);
  if (r.interface_records_omitted > 0) {
    c["frames_of_unlisted_interfaces"] = r.interface_records_omitted;
  }
  c["timing"] = timingJson(r);
  c["clock"] = clockJson(r);
  c["duplicates"] = r.duplicates.count;
  if (r.probe.probed > 0 || !r.probe_note.empty()) c["probe"] = probeJson(r);
  if (r.truncation.any()) c["truncated"] = truncationJson(r.truncation);
  if (!r.coverage.not_judged.empty()) c["not_judged"] = notJudgedJson(r);
  c["layout"] = layoutJson(r);
  c["findings"] = findingsJson(r);
  if (r.baseline) {
    c["baseline"] = baselineJson(r);
    c["baseline_absent"] = baselineAbsentJson(r);
  }
  c["incidents"] = incidentsJson(r);
  if (r.incidents_omitted > 0) c["incidents_omitted"] = r.incidents_omitted;
  if (r.baseline) c["baseline_absent_incidents"] = baselineAbsentIncidentsJson(r);
  c["axes"] = axesJson(r);
  Json messages = Json::array();
  for (const DriveMessage& m : r.drive_messages) messages.push_back(driveMessageJson(r, m));
  c["drive_messages"] = std::move(messages);
  if (r.drive_messages_omitted > 0) c["drive_messages_omitted"] = r.drive_messages_omitted;
  Json esc = Json::array();
  for (const EscErrorDelta& d : r.esc_errors) esc.push_back(escErrorJson(r, d));
  c["esc_errors"] = std::move(esc);
  Json links = Json::array();
  for (const LinkFault& f : r.link_faults) links.push_back(linkFaultJson(f));
  c["link_faults"] = std::move(links);
  if (r.esc_errors_omitted > 0) c["esc_errors_omitted"] = r.esc_errors_omitted;
  if (!r.mailbox_notes.empty()) {
    Json notes = Json::array();
    for (const MailboxNote& n : r.mailbox_notes) {
      Json j{{"frame", n.frame}};
      putSlave(j, r, n.slave);
      j["text"] = n.text;
      notes.push_back(std::move(j));
    }
    c["mailbox_notes"] = std::move(notes);
  }
  c["summary"] = {{"error", r.count(Severity::Error)},
                  {"warning", r.count(Severity::Warning)},
                  {"info", r.count(Severity::Info)}};
  if (r.error) c["error"] = *r.error;
  return c;
}

}  // namespace ncservo::report::detail

namespace ncservo::report {

ReportedCapture reportedCaptureOf(const CaptureReport& report, Verdict verdict) {
  // The one reading of a capture's JSON: a capture validated now is what its report would hold.
  const detail::Json document{
      {"captures", detail::Json::array({detail::captureJson(report, verdict)})}};
  Result<ReportFile> read = parseReportFile(document.dump(), report.path);
  if (!read || read->captures.empty()) {
    ReportedCapture unread;
    unread.path = report.path;
    return unread;
  }
  return std::move(read->captures.front());
}

}  // namespace ncservo::report

namespace ncservo::report::detail {

void writeJson(const ReportSink& sink, const std::vector<CaptureReport>& reports) {
  Json j;
  j["tool"] = {{"name", "ncservo"}, {"version", NCSERVO_VERSION}};
  Json captures = Json::array();
  for (const CaptureReport& r : reports) captures.push_back(captureJson(r, sink.judge.verdict(r)));
  j["captures"] = std::move(captures);
  std::fputs((j.dump(2) + "\n").c_str(), sink.out);
}

}  // namespace ncservo::report::detail
