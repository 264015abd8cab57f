// The HTML page's incident cards (docs/html-report.md, docs/incidents.md): each incident's chain —
// evidence, the incident, its recovery — on one timeline, drawn by Chart.js as the page's other
// charts are.
#include <fmt/format.h>

#include "ncservo/incidents/causes.hpp"
#include "report_format.hpp"

namespace ncservo::report::detail {

namespace {
double msFrom(const Stamp& at, const Stamp& from) {
  return static_cast<double>(at.time_ns - from.time_ns) / 1e6;
}
}  // namespace

Json incidentsHtmlJson(const CaptureReport& r) {
  Json list = Json::array();
  for (std::size_t n = 0; n < r.incidents.size(); ++n) {
    const Incident& incident = r.incidents[n];
    Json evidence = Json::array();
    for (const IncidentEvidence& e : incident.evidence) {
      evidence.push_back({msFrom(e.at, incident.at), e.at.frame, e.what});
    }
    Json recovery = Json::array();
    if (incident.error_clear) {
      recovery.push_back({msFrom(*incident.error_clear, incident.at), incident.error_clear->frame,
                          "errors cleared"});
    }
    if (incident.reenabled) {
      recovery.push_back({msFrom(*incident.reenabled, incident.at), incident.reenabled->frame,
                          incident.kind == IncidentKind::Esm ? "back in OP" : "running again"});
    }
    list.push_back({{"n", n + 1},
                    {"title", incidentHeadline(incident, axisLabel(r, incident.axis))},
                    {"axis", axisLabel(r, incident.axis)},
                    {"frame", incident.at.frame},
                    {"time", seconds(r, incident.at)},
                    {"time_of_day", dayTimeOf(r, incident.at)},
                    {"cause", causeDef(incident.cause).name},
                    {"text", incident.cause_text},
                    {"evidence", std::move(evidence)},
                    {"recovery", std::move(recovery)},
                    {"end", msFrom(incident.end, incident.at)},
                    {"end_frame", incident.end.frame}});
  }
  return list;
}

const char* const kIncidentStyle = R"css(
.incidents{display:flex;flex-wrap:wrap;gap:1em}
figure.incident{margin:0;border:1px solid #ddd;border-left:4px solid #c62828;padding:.5em;width:620px}
figure.incident figcaption{font-size:.9em;margin-bottom:.3em}
figure.incident ol{font-size:.85em;margin:.3em 0 0 1.2em;padding:0}
)css";

// incidentCards(capture, section, index): a card per incident, its chain on one time axis (ms from
// the incident): the evidence, the incident, the recovery, each a point with its frame.
const char* const kIncidentScript = R"js(
function incidentCards(capture, section, index) {
  section.appendChild(el('h3', {}, 'Incidents'));
  if (!capture.incidents.length) {
    section.appendChild(el('p', {class: 'note'}, 'No drive fault, bus outage or fall from OP.'));
    return;
  }
  section.appendChild(el('p', {class: 'note'}, 'Each drive fault, bus outage and fall from OP, with the cause the first matching row of the cause table names (docs/incidents.md): its evidence, the incident (dashed line) and its recovery, in ms from the incident.'));
  const cards = el('div', {class: 'incidents'});
  section.appendChild(cards);
  for (const incident of capture.incidents) {
    const figure = el('figure', {class: 'incident', id: `incident-${index}-${incident.n}`, 'data-cause': incident.cause, 'data-axis': incident.axis});
    figure.appendChild(el('figcaption', {}, `incident ${incident.n}: ${incident.title} at frame ${incident.frame}, ${incident.time.toFixed(3)} s (${incident.time_of_day}) — ${incident.cause}: ${incident.text}`));
    const canvas = el('canvas', {width: 600, height: 150});
    figure.appendChild(canvas);
    const list = el('ol');
    const chain = [...incident.evidence.map(e => [e[0], e[1], e[2]]), [0, incident.frame, incident.title], ...incident.recovery];
    for (const c of chain) list.appendChild(el('li', {}, `frame ${c[1]} (${c[0].toFixed(1)} ms): ${c[2]}`));
    figure.appendChild(list);
    cards.appendChild(figure);
    const lanes = ['recovery', 'incident', 'evidence'];
    const point = (c, lane) => ({x: c[0], y: lane, frame: c[1], what: c[2]});
    const xs = chain.map(c => c[0]).concat([incident.end]);
    const span = Math.max(1, Math.max(...xs) - Math.min(...xs));
    new Chart(canvas, {
      type: 'scatter',
      data: {datasets: [
        {label: 'evidence', data: incident.evidence.map(e => point(e, 2)), pointRadius: 5, backgroundColor: '#b26a00'},
        {label: 'incident', data: [point([0, incident.frame, incident.title], 1)], pointRadius: 7, pointStyle: 'crossRot', borderColor: '#c62828', borderWidth: 3},
        {label: 'recovery', data: incident.recovery.map(r => point(r, 0)), pointRadius: 5, backgroundColor: '#2e7d32'}]},
      options: {
        animation: false, responsive: false,
        scales: {
          x: {type: 'linear', min: Math.min(...xs) - span * 0.05, max: Math.max(...xs) + span * 0.05, title: {display: true, text: 'ms from the incident'}},
          y: {min: -0.5, max: 2.5, afterBuildTicks: axis => { axis.ticks = [0, 1, 2].map(value => ({value})); }, ticks: {callback: v => lanes[v] || ''}}
        },
        plugins: {legend: {display: false}, tooltip: {callbacks: {label: item => `frame ${item.raw.frame}: ${item.raw.what}`}}}
      },
      plugins: [{id: 'ncservoIncident', beforeDatasetsDraw(chart) {
        const {ctx, chartArea: a, scales: {x}} = chart;
        ctx.save(); ctx.strokeStyle = '#c62828'; ctx.setLineDash([4, 3]);
        const at = x.getPixelForValue(0);
        ctx.beginPath(); ctx.moveTo(at, a.top); ctx.lineTo(at, a.bottom); ctx.stroke(); ctx.restore();
      }}]
    });
  }
}
)js";

}  // namespace ncservo::report::detail
