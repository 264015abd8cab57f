#include "ncservo/telemetry/live_metrics.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "ncservo/incidents/causes.hpp"
#include "ncservo/telemetry/exposition.hpp"

namespace ncservo {

namespace {

constexpr std::array<double, kCycleBucketCount> cycleBuckets() {
  std::array<double, kCycleBucketCount> bounds{};
  std::size_t n = 0;
  for (const int nominal : kCycleNominalsUs) {
    // In tenths of a microsecond first: exact, so each bound prints as written (0.0001125).
    for (const int tenths : kCycleBucketTenths) bounds[n++] = nominal * tenths / 10.0 / 1e6;
  }
  std::sort(bounds.begin(), bounds.end());
  return bounds;
}

constexpr std::array<double, kLatencyBucketCount> latencyBuckets() {
  std::array<double, kLatencyBucketCount> bounds{};
  std::size_t n = 0;
  for (int decade_us = 1; n < kLatencyBucketCount; decade_us *= 10) {
    for (const int step : {1, 2, 5}) {
      if (n < kLatencyBucketCount) bounds[n++] = decade_us * step / 1e6;
    }
  }
  return bounds;
}

constexpr bool strictlyAscending(const auto& bounds) {
  return std::adjacent_find(bounds.begin(), bounds.end(),
                            [](double a, double b) { return a >= b; }) == bounds.end();
}

// A station address as the labels write it, as the JSON report does ("0x03E9").
std::string stationLabel(std::uint16_t station) {
  return fmt::format("0x{:04X}", station);
}

}  // namespace

const std::array<double, kCycleBucketCount> kCycleBuckets = cycleBuckets();
const std::array<double, kLatencyBucketCount> kLatencyBuckets = latencyBuckets();
static_assert(strictlyAscending(cycleBuckets()), "two nominal cycles give the same bound");
static_assert(strictlyAscending(latencyBuckets()));

template <std::size_t N>
void FixedHistogram<N>::observe(double seconds) {
  const auto bucket = std::lower_bound(bounds->begin(), bounds->end(), seconds) - bounds->begin();
  ++counts[static_cast<std::size_t>(bucket)];  // le: a sample on a bound counts in its bucket
  sum += seconds;
}
template struct FixedHistogram<kCycleBucketCount>;
template struct FixedHistogram<kLatencyBucketCount>;

// ---- The capture thread's side ----

LiveMetrics::LiveMetrics(const RuleSettings& settings) {
  snapshot_.enabled = settings.enabled;
  snapshot_.severity = settings.severity;
}

MetricsSnapshot::Axis& LiveMetrics::axis(std::uint16_t index) {
  if (index >= snapshot_.axes.size()) {
    const std::size_t from = snapshot_.axes.size();
    snapshot_.axes.resize(index + 1u);
    for (std::size_t i = from; i < snapshot_.axes.size(); ++i) {
      snapshot_.axes[i].name = fmt::format("axis{}", i);  // until the layout names it
    }
  }
  return snapshot_.axes[index];
}

void LiveMetrics::onFrame(const Validator& validator) {
  const FrameTiming& timing = validator.frameTiming();
  if (timing.interval_ns) snapshot_.cycle.observe(static_cast<double>(*timing.interval_ns) / 1e9);
  if (timing.latency_ns) snapshot_.latency.observe(static_cast<double>(*timing.latency_ns) / 1e9);
  // docs/drive-messages.md: each counter's rises, per slave and port (a broadcast read's sum
  // names no slave, and is left out).
  for (const EscErrorDelta& d : validator.escErrors().frameDeltas()) {
    if (d.broadcast || !d.slave.station) continue;
    const char* counter = diag::escCounterName(d.counter);
    auto it = std::find_if(snapshot_.esc.begin(), snapshot_.esc.end(), [&](const EscErrorCount& e) {
      return e.station == *d.slave.station && e.port == d.port && e.counter == counter;
    });
    if (it == snapshot_.esc.end()) {
      it = snapshot_.esc.insert(snapshot_.esc.end(),
                                EscErrorCount{*d.slave.station, d.port, counter, 0});
    }
    it->count += d.delta;
  }
}

void LiveMetrics::onFindings(const std::vector<Finding>& findings) {
  for (const Finding& f : findings) {
    const auto rule = static_cast<std::size_t>(f.rule);
    ++(f.axis ? axis(*f.axis).findings : snapshot_.bus_findings)[rule];
  }
}

void LiveMetrics::refresh(const CapturePipeline& pipeline, std::uint64_t frames,
                          std::uint64_t capture_dropped) {
  snapshot_.frames = frames;
  snapshot_.capture_dropped = capture_dropped;
  snapshot_.clock = pipeline.clockStage().choice().source;
  const Validator* validator = pipeline.validator();
  if (validator == nullptr) return;  // still learning the layout
  for (const AxisInfo& info : validator->decoder().axes()) {
    MetricsSnapshot::Axis& a = axis(info.index);
    if (a.name != info.name) a.name = info.name;
    if (const AxisModel* model = validator->axis(info.index)) {
      a.state = model->state();
      a.telegram_failures = model->totalFailures();
    }
  }
  snapshot_.lost_cycles = validator->bus().lostCycles();
  snapshot_.wkc_errors = validator->bus().wkcErrors();
  if (const IncidentDetector* detector = pipeline.incidents()) {
    const std::vector<Incident>& incidents = detector->incidents();
    // Counted once their cause is final: a counter never goes back (docs/incidents.md#link-fault).
    for (; incidents_counted_ < incidents.size() && detector->causeFinal(incidents_counted_);
         ++incidents_counted_) {
      const Incident& incident = incidents[incidents_counted_];
      const auto cause = static_cast<std::size_t>(incident.cause);
      ++(incident.axis ? axis(*incident.axis).incidents : snapshot_.bus_incidents)[cause];
    }
  }
  snapshot_.dc.clear();
  for (const DcStation& station : validator->dc().stations()) {
    if (station.slave.station && station.last_difference_ns) {
      snapshot_.dc.push_back(
          {*station.slave.station, static_cast<double>(*station.last_difference_ns) / 1e9});
    }
  }
}

// ---- The scrapes' side ----

bool MetricsBoard::tryPublish(const MetricsSnapshot& snapshot) {
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return false;
  published_ = snapshot;
  return true;
}

void MetricsBoard::publish(const MetricsSnapshot& snapshot) {
  const std::lock_guard lock(mutex_);
  published_ = snapshot;
}

std::string MetricsBoard::scrape() const {
  MetricsSnapshot copy;
  {
    const std::lock_guard lock(mutex_);
    copy = published_;
  }
  return exposeMetrics(copy);
}

// ---- The exposition ----

namespace {

std::string name(const char* family) {
  return std::string(kMetricPrefix) + family;
}

// Each rule's series: on the bus for a bus rule, on each axis for an axis rule, both for a
// slave rule (a slave that is an axis names it); any other that counted, too.
void exposeFindings(const MetricsSnapshot& s, Exposition& out) {
  out.family(name("findings_total"), MetricType::Counter,
             "Findings by rule (docs/rules.md), its severity, and axis (empty: the bus)");
  for (const RuleDef& rule : kRules) {
    const auto r = static_cast<std::size_t>(rule.id);
    const char* severity = severityName(s.severity[r]);
    if ((s.enabled[r] && rule.kind != RuleKind::Axis) || s.bus_findings[r] > 0) {
      out.sample({{"rule", rule.code}, {"severity", severity}, {"axis", ""}}, s.bus_findings[r]);
    }
    for (const MetricsSnapshot::Axis& a : s.axes) {
      if ((s.enabled[r] && rule.kind != RuleKind::Bus) || a.findings[r] > 0) {
        out.sample({{"rule", rule.code}, {"severity", severity}, {"axis", a.name}}, a.findings[r]);
      }
    }
  }
}

void exposeAxes(const MetricsSnapshot& s, Exposition& out) {
  out.family(name("axis_state"), MetricType::Gauge,
             "1 for the drive state the axis is in (docs/protocol.md section 6), 0 for the others");
  for (const MetricsSnapshot::Axis& a : s.axes) {
    for (std::size_t i = 0; i < kStateRows.size(); ++i) {
      const DriveState state = kStateRows[i].state;
      bool before = false;
      for (std::size_t j = 0; j < i; ++j) before = before || kStateRows[j].state == state;
      if (before) continue;  // a state of several rows, once
      out.sample({{"axis", a.name}, {"state", driveStateName(state)}},
                 std::uint64_t{a.state == state ? 1u : 0u});
    }
  }
  out.family(name("telegram_failures"), MetricType::Gauge,
             "The axis's telegram failure counter as the drive counts it (docs/rules.md#com-003)");
  for (const MetricsSnapshot::Axis& a : s.axes) {
    out.sample({{"axis", a.name}}, std::uint64_t{a.telegram_failures});
  }
}

void exposeIncidents(const MetricsSnapshot& s, Exposition& out) {
  out.family(name("incidents_total"), MetricType::Counter,
             "Incidents by cause (docs/incidents.md#causes) and axis (empty: the bus or a slave "
             "that is no axis)");
  for (const CauseDef& cause : kCauses) {
    const auto c = static_cast<std::size_t>(cause.id);
    out.sample({{"cause", cause.name}, {"axis", ""}}, s.bus_incidents[c]);
    for (const MetricsSnapshot::Axis& a : s.axes) {
      out.sample({{"cause", cause.name}, {"axis", a.name}}, a.incidents[c]);
    }
  }
}

void exposeSlaves(const MetricsSnapshot& s, Exposition& out) {
  out.family(name("dc_system_time_difference_seconds"), MetricType::Gauge,
             "The last system time difference (0x092C) read of each slave's distributed clock");
  for (const DcDifference& dc : s.dc) {
    out.sample({{"station", stationLabel(dc.station)}}, dc.seconds);
  }
  out.family(name("esc_errors_total"), MetricType::Counter,
             "Rises of the ESC error counters read, per slave, port and counter");
  for (const EscErrorCount& esc : s.esc) {
    const std::string port = fmt::format("{}", esc.port);
    out.sample({{"station", stationLabel(esc.station)}, {"port", port}, {"counter", esc.counter}},
               esc.count);
  }
}

}  // namespace

std::string exposeMetrics(const MetricsSnapshot& s) {
  Exposition out;
  out.family(name("frames_total"), MetricType::Counter,
             "Frames captured, of any kind (validate's frames)");
  out.sample({}, s.frames);
  out.family(name("capture_dropped_total"), MetricType::Counter,
             "Frames the kernel and the interface dropped: the capture lost them, not the bus");
  out.sample({}, s.capture_dropped);
  out.family(name("cycle_seconds"), MetricType::Histogram,
             "Intervals between consecutive master copies of each cyclic frame (docs/timing.md)");
  out.histogram({}, {*s.cycle.bounds, s.cycle.counts, s.cycle.sum});
  out.family(name("return_latency_seconds"), MetricType::Histogram,
             "Time from a master copy to its returned copy, at the capture point");
  out.histogram({}, {*s.latency.bounds, s.latency.counts, s.latency.sum});
  out.family(
      name("lost_cycles_total"), MetricType::Counter,
      "Cycles lost: missing in the gaps COM-002 judges, or whose frame never came back (COM-004)");
  out.sample({}, s.lost_cycles);
  out.family(name("wkc_errors_total"), MetricType::Counter,
             "Returned process-data datagrams whose working counter was not the expected one");
  out.sample({}, s.wkc_errors);
  exposeAxes(s, out);
  exposeFindings(s, out);
  exposeIncidents(s, out);
  out.family(name("clock_source"), MetricType::Gauge,
             "1 for the clock that times the capture (docs/timing.md#the-clock), 0 for the others");
  for (const ClockSourceRow& row : kClockSources) {
    out.sample({{"source", row.name}}, std::uint64_t{s.clock == row.source ? 1u : 0u});
  }
  exposeSlaves(s, out);
  out.family(name("mqtt_dropped_total"), MetricType::Counter,
             "Messages monitor --mqtt dropped, oldest first, while its queue was full");
  out.sample({}, s.mqtt_dropped);
  return out.text();
}

}  // namespace ncservo
