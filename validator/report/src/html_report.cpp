#include <fmt/format.h>

#include <cstring>
#include <nlohmann/json.hpp>
#include <string>

#include "ncservo/protocol/drive_state.hpp"
#include "ncservo/report/chartjs_source.hpp"
#include "ncservo/report/report.hpp"
#include "report_format.hpp"

namespace ncservo::report {

namespace {
using detail::Json;
using detail::seconds;
using detail::slaveIsAxis;
using detail::slaveOfAxis;

// The findings listed in the table, per capture; past it the page says how many were left out.
constexpr std::size_t kHtmlMaxTableRows = 20000;

double milliseconds(std::int64_t ns) {
  return static_cast<double>(ns) / 1e6;
}

// Every rule the page names: its slug and the field-table rows it reads (rules.hpp Reads).
Json rulesJson() {
  Json rules = Json::object();
  for (const RuleDef& rule : kRules) {
    Json reads = Json::array();
    for (const FieldRead& read : fieldsRead(rule.reads)) reads.push_back(read.field->filter);
    rules[rule.code] = {{"slug", rule.slug},
                        {"summary", rule.summary},
                        {"anchor", ruleAnchor(rule)},
                        {"reads", std::move(reads)}};
  }
  return rules;
}

Json timelineJson(const FindingTimeline& t) {
  Json traces = Json::array();
  for (const BitTrace& trace : t.traces) {
    Json changes = Json::array();
    for (const auto& [at_ns, value] : trace.changes)
      changes.push_back({milliseconds(at_ns), value});
    const unsigned width = trace.through_class ? 1u
                           : trace.field->mask == 0
                               ? 8u * wordDef(trace.field->word).size
                               : static_cast<unsigned>(popcount64(trace.field->mask));
    const std::string name = std::string(trace.field->filter).substr(std::strlen("ncservo."));
    traces.push_back({{"field", trace.field->filter},
                      {"label", trace.through_class ? name + " (class)" : name},
                      {"bits", width},
                      {"changes", std::move(changes)}});
  }
  Json j{{"finding", t.finding},
         {"start", milliseconds(t.start_ns)},
         {"end", milliseconds(t.end_ns)},
         {"since", t.since_ns ? Json(milliseconds(*t.since_ns)) : Json(nullptr)},
         {"allowed", t.allowed_ns ? Json::array({milliseconds(t.allowed_ns->first),
                                                 milliseconds(t.allowed_ns->second)})
                                  : Json(nullptr)},
         {"clipped", t.clipped},
         {"traces", std::move(traces)}};
  return j;
}

Json saidJson(const DriveMessage& m) {
  return {m.frame, describeDriveMessage(m),
          m.request_frame ? Json(*m.request_frame) : Json(nullptr)};
}

// docs/drive-messages.md: the links the ESC counters name and what slaves that are no axis said.
Json busSaidJson(const CaptureReport& r) {
  Json links = Json::array();
  for (const LinkFault& f : r.link_faults) links.push_back({f.frame, linkFaultText(f), f.errors});
  Json others = Json::array();
  for (const DriveMessage& m : r.drive_messages) {
    if (slaveIsAxis(r, m.slave)) continue;
    Json row = saidJson(m);
    row.push_back(slaveName(m.slave));
    others.push_back(std::move(row));
  }
  return {{"links", std::move(links)}, {"others", std::move(others)}};
}

Json captureJson(const CaptureReport& r, Verdict verdict) {
  Json findings = Json::array();
  for (std::size_t i = 0; i < r.findings.size() && i < kHtmlMaxTableRows; ++i) {
    const Finding& f = r.findings[i];
    findings.push_back({ruleDef(f.rule).code, severityName(f.severity), axisLabel(r, f.axis),
                        f.at.frame, seconds(r, f.at), f.message});
  }
  Json timelines = Json::array();
  for (const FindingTimeline& t : r.timelines.drawn) {
    if (t.finding < kHtmlMaxTableRows) timelines.push_back(timelineJson(t));
  }
  Json axes = Json::array();
  for (const AxisSummary& a : r.axes) {
    Json states = Json::array();
    for (const StateChange& s : a.timeline) {
      states.push_back(
          {seconds(r, s.at), driveStateName(s.state), s.transition ? s.transition : ""});
    }
    Json errors = Json::array();
    for (const ErrorHistoryEntry& e : a.error_history) {
      errors.push_back({seconds(r, e.at), sewCauseText(*e.cause),
                        fmt::format("0x{:04X}", e.cause->canopen), e.at.frame});
    }
    // docs/drive-messages.md: what the drive itself said, beside the history kept from SEW.
    Json said = Json::array();
    for (const DriveMessage& m : r.drive_messages) {
      if (slaveOfAxis(r, a.index, m.slave)) said.push_back(saidJson(m));
    }
    axes.push_back({{"name", a.name},
                    {"state", a.state ? Json(driveStateName(*a.state)) : Json(nullptr)},
                    {"states", std::move(states)},
                    {"states_omitted", a.timeline_omitted},
                    {"errors", std::move(errors)},
                    {"said", std::move(said)}});
  }
  // The timing statistics' deviation histograms (docs/timing.md), in µs from the nominal.
  const auto histogram = [](const std::optional<SeriesSummary>& series) {
    Json bins = Json::array();
    if (!series) return bins;
    for (const HistogramBin& bin : series->histogram)
      bins.push_back({static_cast<double>(bin.from_ns) / 1e3, static_cast<double>(bin.to_ns) / 1e3,
                      bin.count});
    return bins;
  };
  auto number = [](const std::optional<double>& v) { return v ? Json(*v) : Json(nullptr); };
  return {
      {"path", r.path},
      {"verdict", verdictName(verdict)},
      {"reason", r.coverage.complete() || r.unopened() ? Json(nullptr) : Json(r.coverage.reason)},
      {"error", r.error ? Json(*r.error) : Json(nullptr)},
      {"counts",
       {{"error", r.count(Severity::Error)},
        {"warning", r.count(Severity::Warning)},
        {"info", r.count(Severity::Info)}}},
      {"frames", r.frames},
      {"start", r.frames > 0 ? detail::startOf(r) : std::string()},
      {"cycles", r.cycles},
      {"cycle_time_us",
       {{"median", number(r.cycle_time.median_us)},
        {"p99", number(r.cycle_time.p99_us)},
        {"max", number(r.cycle_time.max_us)}}},
      {"layout_source", layoutSourceName(r.layout_source)},
      {"clock", describeClock(r.clock)},
      {"duplicates", r.duplicates.count},
      {"findings", std::move(findings)},
      {"findings_total", r.findings.size()},
      {"baseline", r.baseline ? Json(fmt::format("against the baseline {}: {}", r.baseline_path,
                                                 describeBaseline(r)))
                              : Json(nullptr)},
      {"timelines", std::move(timelines)},
      {"timelines_omitted", r.timelines.omitted},
      {"axes", std::move(axes)},
      {"incidents", detail::incidentsHtmlJson(r)},
      {"bus_said", busSaidJson(r)},
      {"cycle_histogram", histogram(r.timing.cycle)},
      {"latency_histogram", histogram(r.timing.latency)}};
}

// The page's data, safe inside a <script> element: no "<" at all ("</script>" cannot end it).
std::string scriptSafe(const std::string& json) {
  std::string out;
  out.reserve(json.size());
  for (char c : json) {
    if (c == '<') {
      out += "\\u003c";
    } else {
      out += c;
    }
  }
  return out;
}

constexpr const char* kStyle = R"css(
body{font:14px/1.4 system-ui,sans-serif;margin:1.5em;color:#222}
h1{font-size:1.4em}h2{font-size:1.2em;margin-top:1.6em}h3{font-size:1.05em}
.verdict{display:inline-block;padding:.2em .6em;border-radius:4px;color:#fff;font-weight:bold}
.v-fail,.v-unreadable{background:#c62828}.v-warn{background:#b26a00}.v-pass{background:#2e7d32}.v-no.servo{background:#6d6d6d}
.sev-error{color:#c62828;font-weight:bold}.sev-warning{color:#b26a00}.sev-info{color:#1565c0}
table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:.2em .5em;text-align:left;vertical-align:top}
th.sortable{cursor:pointer;background:#f3f3f3}th.sortable:hover{background:#e6e6e6}
.filters label{margin-right:1em}.note{color:#555;font-size:.9em}
.timelines{display:flex;flex-wrap:wrap;gap:1em}
figure.timeline{margin:0;border:1px solid #ddd;padding:.5em;width:520px}
figure.timeline figcaption{font-size:.9em;margin-bottom:.3em}
.axis{border-top:1px solid #ddd;margin-top:1em}
.history{display:flex;flex-wrap:wrap;gap:1.5em;align-items:flex-start}
caption{text-align:left;font-weight:bold;font-size:.9em;padding:.2em 0}
)css";

// The page's own code: the table's sorting and filtering, and what each chart is given. Drawing is
// Chart.js's.
constexpr const char* kScript = R"js(
'use strict';
const data = JSON.parse(document.getElementById('ncservo-data').textContent);
const el = (tag, attrs, text) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
};
const severityRank = {error: 0, warning: 1, info: 2};
function windowPlugin(timeline) {
  return {
    id: 'ncservoWindow',
    beforeDatasetsDraw(chart) {
      const {ctx, chartArea: a, scales: {x}} = chart;
      ctx.save();
      if (timeline.allowed !== null) {
        const from = Math.max(a.left, x.getPixelForValue(timeline.allowed[0]));
        const to = Math.min(a.right, x.getPixelForValue(timeline.allowed[1]));
        ctx.fillStyle = 'rgba(46,125,50,0.15)';
        ctx.fillRect(from, a.top, Math.max(to - from, 1), a.bottom - a.top);
      }
      ctx.strokeStyle = '#000';
      ctx.setLineDash([4, 3]);
      ctx.lineWidth = 1.5;
      const at = x.getPixelForValue(0);
      ctx.beginPath(); ctx.moveTo(at, a.top); ctx.lineTo(at, a.bottom); ctx.stroke();
      ctx.restore();
    }
  };
}
function drawTimeline(canvas, timeline) {
  const lanes = timeline.traces.length;
  const datasets = timeline.traces.map((trace, i) => {
    const base = (lanes - 1 - i) * 1.5;
    const top = Math.max(1, ...trace.changes.map(c => c[1]));
    const points = trace.changes.map(c => ({x: c[0], y: base + (trace.bits === 1 ? c[1] : c[1] / top), v: c[1]}));
    const last = trace.changes[trace.changes.length - 1];
    points.push({x: timeline.end, y: points[points.length - 1].y, v: last[1]});
    return {label: trace.field, data: points, stepped: 'before', borderWidth: 2, pointRadius: 0,
            borderColor: `hsl(${(i * 67) % 360},60%,40%)`, fill: false};
  });
  new Chart(canvas, {
    type: 'line',
    data: {datasets},
    options: {
      animation: false, responsive: false, parsing: {xAxisKey: 'x', yAxisKey: 'y'},
      scales: {
        x: {type: 'linear', min: timeline.start, max: timeline.end, title: {display: true, text: 'ms from the finding'}},
        y: {min: -0.25, max: lanes * 1.5 - 0.25,
            afterBuildTicks: axis => { axis.ticks = timeline.traces.map((t, i) => ({value: (lanes - 1 - i) * 1.5 + 0.5})); },
            ticks: {autoSkip: false, callback: (value, index) => timeline.traces[index] ? timeline.traces[index].label : ''}}
      },
      plugins: {
        legend: {display: false},
        tooltip: {callbacks: {label: item => `${timeline.traces[item.datasetIndex].label} = ${item.raw.v}`}}
      }
    },
    plugins: [windowPlugin(timeline)]
  });
}
function drawStates(canvas, axis, end) {
  const names = data.states;
  const points = axis.states.map(s => ({x: s[0], y: names.indexOf(s[1]), name: s[1]}));
  if (points.length) points.push({x: end, y: points[points.length - 1].y, name: points[points.length - 1].name});
  new Chart(canvas, {
    type: 'line',
    data: {datasets: [{label: axis.name, data: points, stepped: 'before', pointRadius: 2, borderColor: '#1565c0'}]},
    options: {
      animation: false, responsive: false,
      scales: {x: {type: 'linear', title: {display: true, text: 's'}},
               y: {min: 0, max: names.length - 1, ticks: {stepSize: 1, autoSkip: false, callback: v => names[v]}}},
      plugins: {legend: {display: false}, tooltip: {callbacks: {label: item => item.raw.name}}}
    }
  });
}
function drawHistogram(canvas, bins, what, counted) {
  new Chart(canvas, {
    type: 'bar',
    data: {labels: bins.map(b => `${b[0]}…${b[1]}`), datasets: [{label: counted, data: bins.map(b => b[2]), backgroundColor: '#1565c0'}]},
    options: {animation: false, responsive: false, plugins: {legend: {display: false}},
              scales: {x: {title: {display: true, text: what}}, y: {title: {display: true, text: counted}}}}
  });
}
function findingsTable(capture, section, index) {
  const filters = el('div', {class: 'filters'});
  const choices = (name, values) => {
    const label = el('label', {}, name + ' ');
    const select = el('select', {'data-filter': name});
    select.appendChild(el('option', {value: ''}, 'all'));
    for (const v of [...new Set(values)].sort()) select.appendChild(el('option', {value: v}, v));
    label.appendChild(select);
    filters.appendChild(label);
    return select;
  };
  const severity = choices('severity', capture.findings.map(f => f[1]));
  const rule = choices('rule', capture.findings.map(f => f[0]));
  const axis = choices('axis', capture.findings.map(f => f[2]));
  const shown = el('span', {class: 'note'});
  filters.appendChild(shown);
  section.appendChild(filters);
  const table = el('table', {class: 'findings', id: `findings-${index}`});
  const head = el('tr');
  const columns = ['#', 'time (s)', 'severity', 'rule', 'axis', 'frame', 'message'];
  columns.forEach((c, i) => { const th = el('th', {class: 'sortable', 'data-column': i}, c); head.appendChild(th); });
  const thead = el('thead'); thead.appendChild(head); table.appendChild(thead);
  const body = el('tbody'); table.appendChild(body);
  const drawn = new Set(capture.timelines.map(t => t.finding));
  const rows = capture.findings.map((f, n) => {
    const tr = el('tr', {class: 'finding', 'data-severity': f[1], 'data-rule': f[0], 'data-axis': f[2]});
    const cells = [n + 1, f[4].toFixed(6), f[1], f[0], f[2], f[3], f[5]];
    cells.forEach((c, i) => {
      const td = el('td', {}, String(c));
      if (i === 2) td.className = 'sev-' + f[1];
      if (i === 3) td.title = data.rules[f[0]].slug;
      tr.appendChild(td);
    });
    if (drawn.has(n)) {
      const link = el('a', {href: `#timeline-${index}-${n}`}, ' (timeline)');
      tr.lastChild.appendChild(link);
    }
    return {tr, key: [n, f[4], severityRank[f[1]], f[0], f[2], f[3], f[5]]};
  });
  let order = {column: 0, up: true};
  const render = () => {
    const wanted = [severity.value, rule.value, axis.value];
    const visible = rows.filter(r => (!wanted[0] || r.tr.dataset.severity === wanted[0]) &&
      (!wanted[1] || r.tr.dataset.rule === wanted[1]) && (!wanted[2] || r.tr.dataset.axis === wanted[2]));
    visible.sort((a, b) => {
      const x = a.key[order.column], y = b.key[order.column];
      const c = x < y ? -1 : x > y ? 1 : a.key[0] - b.key[0];
      return order.up ? c : -c;
    });
    body.replaceChildren(...visible.map(r => r.tr));
    shown.textContent = `${visible.length} of ${rows.length} shown`;
  };
  head.addEventListener('click', e => {
    const column = Number(e.target.dataset.column);
    if (Number.isNaN(column)) return;
    order = {column, up: order.column === column ? !order.up : true};
    render();
  });
  for (const s of [severity, rule, axis]) s.addEventListener('change', render);
  render();
  section.appendChild(table);
  if (capture.findings_total > capture.findings.length) {
    section.appendChild(el('p', {class: 'note'}, `The first ${capture.findings.length} of ${capture.findings_total} findings are listed (the JSON report has them all).`));
  }
}
// A small table with a caption: its class, the column heads and the rows' cells.
function table(cls, caption, heads, rows) {
  const t = el('table', {class: cls});
  t.appendChild(el('caption', {}, caption));
  const h = el('tr'); heads.forEach(x => h.appendChild(el('th', {}, x))); t.appendChild(h);
  for (const row of rows) { const r = el('tr'); row.forEach(x => r.appendChild(el('td', {}, String(x)))); t.appendChild(r); }
  return t;
}
function captureSection(capture, index) {
  const section = el('section', {class: 'capture', id: `capture-${index}`});
  section.appendChild(el('h2', {}, capture.path));
  const verdict = el('p');
  verdict.appendChild(el('span', {class: 'verdict v-' + capture.verdict.replace(' ', '.'), id: `verdict-${index}`}, capture.verdict.toUpperCase()));
  const c = capture.counts;
  verdict.appendChild(document.createTextNode(` ${c.error} errors, ${c.warning} warnings, ${c.info} info; ${capture.frames} frames, ${capture.cycles} cycles` + (capture.start ? `, from ${capture.start}` : '') + `; layout: ${capture.layout_source}`));
  section.appendChild(verdict);
  if (capture.baseline) section.appendChild(el('p', {class: 'baseline'}, capture.baseline));
  if (capture.reason) section.appendChild(el('p', {}, 'No servo: ' + capture.reason));
  if (capture.error) section.appendChild(el('p', {class: 'sev-error'}, capture.error));
  section.appendChild(el('h3', {}, 'Findings'));
  findingsTable(capture, section, index);
  incidentCards(capture, section, index);
  section.appendChild(el('h3', {}, 'Finding timelines'));
  section.appendChild(el('p', {class: 'note'}, `The bits each rule reads (docs/rules.md), from ${data.frames_around} frames before the condition began to ${data.frames_around} after the finding (dashed black line: the finding's frame); green: the window the rule's timeout allowed. A rule that reads no bits (the bus rules, COM-005) gets none. Drawn: the first ${data.per_rule_and_axis} findings of each rule and axis, at most ${data.max_timelines} in all` + (capture.timelines_omitted ? `; ${capture.timelines_omitted} axis findings not drawn.` : '.')));
  const timelines = el('div', {class: 'timelines'});
  section.appendChild(timelines);
  for (const t of capture.timelines) {
    const f = capture.findings[t.finding];
    const figure = el('figure', {class: 'timeline', id: `timeline-${index}-${t.finding}`, 'data-finding': t.finding, 'data-rule': f[0]});
    figure.appendChild(el('figcaption', {}, `#${t.finding + 1} ${f[0]} ${data.rules[f[0]].slug}, ${f[2]}, frame ${f[3]}` + (t.clipped ? ' (the condition began before the recorded cycles)' : '')));
    const canvas = el('canvas', {width: 500, height: 60 + 28 * t.traces.length});
    figure.appendChild(canvas);
    timelines.appendChild(figure);
    drawTimeline(canvas, t);
  }
  section.appendChild(el('h3', {}, 'Axes'));
  for (const axis of capture.axes) {
    const div = el('div', {class: 'axis', 'data-axis': axis.name});
    div.appendChild(el('h4', {}, `${axis.name}: ${axis.state || 'state unknown'}`));
    const canvas = el('canvas', {width: 900, height: 220});
    div.appendChild(canvas);
    if (axis.states_omitted) div.appendChild(el('p', {class: 'note'}, `${axis.states_omitted} later state changes not kept.`));
    const history = el('div', {class: 'history'});
    if (axis.errors.length) {
      history.appendChild(table('errors', 'Errors ncservo read from SEW', ['time (s)', 'error', 'CANopen', 'frame'], axis.errors.map(e => [e[0].toFixed(6), e[1], e[2], e[3]])));
    } else {
      history.appendChild(el('p', {class: 'note'}, 'No drive errors.'));
    }
    if (axis.said.length) {
      history.appendChild(table('said', 'What the drive said (docs/drive-messages.md)', ['frame', 'message', 'request frame'], axis.said.map(m => [m[0], m[1], m[2] === null ? '' : m[2]])));
    }
    div.appendChild(history);
    section.appendChild(div);
    drawStates(canvas, axis, capture.end);
  }
  const bus = capture.bus_said;
  if (bus.links.length || bus.others.length) {
    section.appendChild(el('h3', {}, 'Links and other slaves'));
    if (bus.links.length) section.appendChild(table('links', 'Links the ESC error counters name', ['frame', 'link', 'errors'], bus.links));
    if (bus.others.length) section.appendChild(table('said', 'What slaves that are no axis said', ['frame', 'message', 'request frame', 'slave'], bus.others.map(m => [m[0], m[1], m[2] === null ? '' : m[2], m[3]])));
  }
  section.appendChild(el('h3', {}, 'Cycle time'));
  const ct = capture.cycle_time_us;
  section.appendChild(el('p', {}, ct.median === null ? 'No cycle measured.' : `median ${ct.median} µs, p99 ${ct.p99} µs, max ${ct.max} µs`));
  section.appendChild(el('p', {class: 'note'}, `Clock: ${capture.clock} (docs/timing.md#the-clock).`));
  if (capture.duplicates > 0) {
    section.appendChild(el('p', {class: 'note'}, `${capture.duplicates} duplicate records ignored (docs/cli.md).`));
  }
  if (capture.cycle_histogram.length) {
    const canvas = el('canvas', {width: 700, height: 260, id: `histogram-${index}`});
    section.appendChild(canvas);
    drawHistogram(canvas, capture.cycle_histogram, 'deviation from the median cycle (µs)', 'cycles');
  }
  if (capture.latency_histogram.length) {
    section.appendChild(el('h3', {}, 'Return latency'));
    section.appendChild(el('p', {class: 'note'}, 'From a master copy to its returned copy, as seen at the capture point (docs/timing.md).'));
    const canvas = el('canvas', {width: 700, height: 260, id: `latency-${index}`});
    section.appendChild(canvas);
    drawHistogram(canvas, capture.latency_histogram, 'deviation from the median latency (µs)', 'frames');
  }
  document.getElementById('captures').appendChild(section);
}
data.captures.forEach(captureSection);
)js";
}  // namespace

const char* detail::htmlStyle() {
  return kStyle;
}

void writeHtml(const ReportSink& sink, const std::vector<CaptureReport>& reports) {
  Json states = Json::array();
  for (std::size_t s = 0; s <= static_cast<std::size_t>(DriveState::NotReadyToSwitchOn); ++s) {
    states.push_back(driveStateName(static_cast<DriveState>(s)));
  }
  Json captures = Json::array();
  std::size_t total[3] = {0, 0, 0};
  for (const CaptureReport& r : reports) {
    Json capture = captureJson(r, sink.judge.verdict(r));
    capture["end"] = static_cast<double>(r.last_time_ns - r.first_time_ns) / 1e9;
    captures.push_back(std::move(capture));
    for (std::size_t s = 0; s < 3; ++s) total[s] += r.counts[s];
  }
  const Json data{{"tool", {{"name", "ncservo"}, {"version", NCSERVO_VERSION}}},
                  {"rules", rulesJson()},
                  {"states", std::move(states)},
                  {"frames_around", TimelineRecorder::kFramesAround},
                  {"per_rule_and_axis", TimelineRecorder::kPerRuleAndAxis},
                  {"max_timelines", TimelineRecorder::kMaxTimelines},
                  {"captures", std::move(captures)}};
  fmt::print(sink.out,
             "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
             "<title>ncservo validate: {} error{}, {} warning{}, {} info</title>\n"
             "<style>{}{}</style>\n</head>\n<body>\n"
             "<h1>ncservo validate report</h1>\n"
             "<p class=\"note\">ncservo {}; rules: docs/rules.md; this page: docs/html-report.md. "
             "It needs no network: Chart.js is inside it.</p>\n"
             "<div id=\"captures\"></div>\n",
             total[2], total[2] == 1 ? "" : "s", total[1], total[1] == 1 ? "" : "s", total[0],
             kStyle, detail::kIncidentStyle, NCSERVO_VERSION);
  fmt::print(sink.out, "<script type=\"application/json\" id=\"ncservo-data\">{}</script>\n",
             scriptSafe(data.dump()));
  std::fputs("<script>\n", sink.out);
  std::fwrite(kChartJs, 1, kChartJsSize, sink.out);
  fmt::print(sink.out, "\n</script>\n<script>{}{}</script>\n</body>\n</html>\n", kScript,
             detail::kIncidentScript);
}

}  // namespace ncservo::report
