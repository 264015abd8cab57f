#!/usr/bin/env python3
"""Checks an HTML report of `ncservo validate` in headless Chromium.

check_html_report.py REPORT.html REPORT.json RULES.json

RULES.json maps each rule ID to the field-table rows it reads, as `ncservo rules --explain` prints
them. The page is loaded from file:// with the network switched off; it must log no console
error, list one table row per finding of the JSON report (same rule, axis and frame, in order),
draw a timeline for some findings, and draw in each timeline exactly the rows its rule reads.
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


def main():
    report, expected_json, rules_json = (pathlib.Path(a) for a in sys.argv[1:4])
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
            print(f"capture {index}: {len(rows)} table rows, {len(drawn)} timelines")
    finally:
        driver.quit()
    for problem in problems:
        print("FAIL:", problem, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
