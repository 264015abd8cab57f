#!/usr/bin/env python3
"""Checks an HTML report of `ncservo validate` in headless Chromium.

check_html_report.py REPORT.html REPORT.json RULES.json [MARKER]

RULES.json maps each rule ID to the field-table rows it reads, as `ncservo rules --explain` prints
them. The page is loaded from file:// with the network switched off; it must log no console
error, list one table row per finding of the JSON report (same rule, axis and frame, in order),
draw a timeline for some findings, and draw in each timeline exactly the rows its rule reads, each
with data; one row per drive message and per link fault of the JSON report. A finding whose rule reads no row gets no timeline and no link; every link leads to a
drawn timeline. Measured in the browser as each chart is drawn again: no two texts (tick labels,
titles) of a timeline or an axis's state chart overlap, and a line at the finding's time spans the plot in MARKER's style
("dashed black", as docs/html-report.md says; default that).
Exit 0 when all hold, 1 with the reasons otherwise.
"""
import json
import pathlib
import sys

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service


def browser():
    options = Options()
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 # no network: every host resolves nowhere, and the proxy is unreachable
                 "--host-resolver-rules=MAP * ~NOTFOUND", "--proxy-server=127.0.0.1:9",
                 "--window-size=1400,1000"):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    options.binary_location = "/usr/bin/chromium"
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)


# Each timeline drawn again with the canvas's drawing calls recorded: every text with its box on
# the canvas (from measureText and the transform it is drawn under) and every stroked path.
MEASURE_JS = """
return [...document.querySelectorAll(arguments[0])].map(figure => {
  const chart = Chart.getChart(figure.querySelector('canvas'));
  const ctx = chart.ctx;
  const texts = [], strokes = [];
  let path = [];
  const corner = (t, x, y) => [t.a * x + t.c * y + t.e, t.b * x + t.d * y + t.f];
  ctx.fillText = function (text, x, y, ...rest) {
    const m = this.measureText(text), t = this.getTransform();
    const l = x - m.actualBoundingBoxLeft, r = x + m.actualBoundingBoxRight;
    const u = y - m.actualBoundingBoxAscent, d = y + m.actualBoundingBoxDescent;
    const c = [corner(t, l, u), corner(t, r, u), corner(t, l, d), corner(t, r, d)];
    if (String(text).trim()) {
      texts.push({text: String(text), box: [Math.min(...c.map(p => p[0])), Math.min(...c.map(p => p[1])),
                                            Math.max(...c.map(p => p[0])), Math.max(...c.map(p => p[1]))]});
    }
    return CanvasRenderingContext2D.prototype.fillText.call(this, text, x, y, ...rest);
  };
  ctx.beginPath = function () { path = []; return CanvasRenderingContext2D.prototype.beginPath.call(this); };
  ctx.moveTo = function (x, y) { path.push([x, y]); return CanvasRenderingContext2D.prototype.moveTo.call(this, x, y); };
  ctx.lineTo = function (x, y) { path.push([x, y]); return CanvasRenderingContext2D.prototype.lineTo.call(this, x, y); };
  ctx.stroke = function (...a) {
    strokes.push({style: String(this.strokeStyle), dash: this.getLineDash(), path: path.slice()});
    return CanvasRenderingContext2D.prototype.stroke.apply(this, a);
  };
  try { chart.draw(); } finally { for (const k of ['fillText', 'beginPath', 'moveTo', 'lineTo', 'stroke']) delete ctx[k]; }
  const x0 = chart.scales.x.getPixelForValue(0), area = chart.chartArea;
  const markers = strokes.filter(s => s.path.length === 2 && s.path.every(p => Math.abs(p[0] - x0) < 0.5) &&
    Math.min(s.path[0][1], s.path[1][1]) <= area.top + 0.5 && Math.max(s.path[0][1], s.path[1][1]) >= area.bottom - 0.5);
  return {finding: Number(figure.dataset.finding), texts, markers: markers.map(s => ({style: s.style, dash: s.dash})),
          points: chart.data.datasets.map(d => d.data.length)};
});
"""

# A marker style as docs/html-report.md names it, and the canvas's strokeStyle and dash for it.
COLOURS = {"black": "#000000", "red": "#ff0000"}


def marker_matches(marker, style):
    dashed = bool(marker["dash"])
    colour = COLOURS.get(style.split()[-1])
    return marker["style"] == colour and dashed == style.startswith("dashed")


def overlaps(a, b, slack=0.5):
    return (a[0] + slack < b[2] and b[0] + slack < a[2] and
            a[1] + slack < b[3] and b[1] + slack < a[3])


def main():
    report, expected_json, rules_json = (pathlib.Path(a) for a in sys.argv[1:4])
    marker_style = sys.argv[4] if len(sys.argv) > 4 else "dashed black"
    expected = json.loads(expected_json.read_text())
    reads = json.loads(rules_json.read_text())
    problems = []
    driver = browser()
    try:
        driver.set_network_conditions(offline=True, latency=0, download_throughput=0,
                                      upload_throughput=0)
        driver.get(report.resolve().as_uri())
        errors = [entry for entry in driver.get_log("browser") if entry["level"] == "SEVERE"]
        problems += [f"console: {entry['message']}" for entry in errors]
        for index, capture in enumerate(expected["captures"]):
            rows = driver.execute_script(
                "return [...document.querySelectorAll(arguments[0])].map(tr =>"
                " [...tr.cells].map(td => td.textContent))", f"#findings-{index} tbody tr")
            want = [[f["rule"], f["axis_name"] or "bus", str(f["frame"])]
                    for f in capture["findings"]]
            got = [[row[3], row[4], row[5]] for row in rows]
            if got != want:
                problems.append(f"capture {index}: {len(got)} table rows, JSON has {len(want)}"
                                f" findings; first differing: "
                                f"{next((g, w) for g, w in zip(got + [None] * len(want), want + [None] * len(got)) if g != w)}")
            drawn = driver.execute_script(
                "return [...document.querySelectorAll(arguments[0])].map(f => ({"
                " rule: f.dataset.rule, finding: Number(f.dataset.finding),"
                " labels: Chart.getChart(f.querySelector('canvas')).data.datasets.map(d => d.label)"
                "}))", f"#capture-{index} figure.timeline")
            if capture["findings"] and not drawn:
                problems.append(f"capture {index}: no finding timeline drawn")
            for figure in drawn:
                finding = capture["findings"][figure["finding"]]
                if finding["rule"] != figure["rule"]:
                    problems.append(f"timeline of finding {figure['finding']}: rule "
                                    f"{figure['rule']}, the JSON has {finding['rule']}")
                if figure["labels"] != reads[figure["rule"]]:
                    problems.append(f"timeline of finding {figure['finding']} ({figure['rule']}):"
                                    f" draws {figure['labels']}, the rule reads "
                                    f"{reads[figure['rule']]}")
            # Links: each to a drawn timeline; none on a finding whose rule reads no row.
            links = driver.execute_script(
                "return [...document.querySelectorAll(arguments[0])].map(tr => {"
                " const a = tr.querySelector('a[href^=\"#timeline-\"]');"
                " return [tr.cells[3].textContent, Number(tr.cells[0].textContent) - 1,"
                " a ? a.getAttribute('href').slice(1) : null,"
                " a ? document.getElementById(a.getAttribute('href').slice(1)) !== null : false]; })",
                f"#findings-{index} tbody tr")
            for rule, finding, target, found in links:
                if target is not None and not found:
                    problems.append(f"finding {finding} ({rule}) links to {target}, which is not on the page")
                if not reads.get(rule) and target is not None:
                    problems.append(f"finding {finding} ({rule}) links to a timeline, its rule reads no row")
            measured = driver.execute_script(MEASURE_JS, f"#capture-{index} figure.timeline")
            for figure in measured:
                name = f"timeline of finding {figure['finding']}"
                if not figure["points"] or min(figure["points"]) < 2:
                    problems.append(f"{name}: draws {figure['points']} points per line")
                texts = figure["texts"]
                for i, a in enumerate(texts):
                    for b in texts[i + 1:]:
                        if overlaps(a["box"], b["box"]):
                            problems.append(f"{name}: labels {a['text']!r} {a['box']} and "
                                            f"{b['text']!r} {b['box']} overlap")
                if not any(marker_matches(m, marker_style) for m in figure["markers"]):
                    problems.append(f"{name}: no {marker_style} line at the finding's time; lines"
                                    f" there: {figure['markers']}")
            # What the drives said and the links the counters name (docs/drive-messages.md): one
            # row each, in the axis's card or, for a slave that is no axis, under the bus.
            said = driver.execute_script(
                "return [...document.querySelectorAll(arguments[0])].map(tr =>"
                " Number(tr.cells[0].textContent))", f"#capture-{index} table.said tr:not(:first-of-type)")
            want_said = [m["frame"] for m in capture.get("drive_messages", [])]
            if sorted(said) != sorted(want_said):
                problems.append(f"capture {index}: drive-message rows at frames {said[:5]}…, the JSON"
                                f" has {want_said[:5]}… ({len(said)} against {len(want_said)})")
            links = driver.execute_script(
                "return [...document.querySelectorAll(arguments[0])].map(tr =>"
                " tr.cells[1].textContent)", f"#capture-{index} table.links tr:not(:first-of-type)")
            want_links = [f["text"] for f in capture.get("link_faults", [])]
            if links != want_links:
                problems.append(f"capture {index}: link rows {links}, the JSON has {want_links}")
            # The axes' state charts: their state names and seconds must not overlap either.
            for chart in driver.execute_script(MEASURE_JS, f"#capture-{index} div.axis"):
                texts = chart["texts"]
                for i, a in enumerate(texts):
                    for b in texts[i + 1:]:
                        if overlaps(a["box"], b["box"]):
                            problems.append(f"capture {index}, a state chart: labels {a['text']!r}"
                                            f" and {b['text']!r} overlap")
                measured.append(chart)
            labels = sum(len(f["texts"]) for f in measured)
            print(f"capture {index}: {len(rows)} table rows, {len(drawn)} timelines, {labels} labels"
                  f" measured")
    finally:
        driver.quit()
    for problem in problems:
        print("FAIL:", problem, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
