#!/usr/bin/env bash
# reports.sh SRC BUILD: the text report's verdict per capture and one line per
# rule and axis (--verbose: every finding); configured axis names in every format; time_utc beside
# each time; several reports in one run (--report FORMAT:FILE), written through a temporary file,
# never over an input or over each other; JUnit skipped cases; SARIF notifications and locations
# (the frame's record in the file). report_schemas.sh checks the same files against the schemas.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

validate() {  # validate EXPECTED_RC ARGS...: ncservo validate into $WORK/out and $WORK/err
  local expected=$1
  shift
  set +e
  "$NCSERVO" validate "$@" >"$WORK/out" 2>"$WORK/err"
  local rc=$?
  set -e
  [ "$rc" = "$expected" ] || fail "validate $*: exit $rc, expected $expected; stderr: $(head -3 "$WORK/err")"
}

# Captures: faults with named axes, a lossy one (many COM-004), nanosecond pcapng, no servo.
"$NCSERVO" simulate --scenario faults --axes 4 --seed 5 -o "$WORK/faults.pcap" \
  --layout-config "$WORK/layout.toml" 2>/dev/null
sed -e "s/name = 'axis0'/name = 'X'/" -e "s/name = 'axis1'/name = 'Y'/" -e "s/name = 'axis2'/name = 'Z'/" -e "s/name = 'axis3'/name = 'W'/" \
  "$WORK/layout.toml" >"$WORK/named.toml"
grep -q "name = 'X'" "$WORK/named.toml" || fail "layout file has no axis0 to rename: $(cat "$WORK/layout.toml")"
"$NCSERVO" simulate --scenario commissioning --axes 2 --loss 0.05 --seed 9 -o "$WORK/lossy.pcap" 2>/dev/null
"$NCSERVO" simulate --scenario faults --axes 4 --seed 3 -o "$WORK/nano.pcapng" 2>/dev/null
gzip -c "$WORK/nano.pcapng" >"$WORK/nano.pcapng.gz"
python3 "$GEN" --axes 2 --cycles 200 -o "$WORK/clean.pcap"
printf 'not a capture\n' >"$WORK/text.pcap"
printf '[[axis]]\nname = "ghost"\noutputs = 0x00090000\ninputs = 0x00090028\n' >"$WORK/ghost.toml"

# Text, one capture per verdict: each capture its own verdict line, the overall verdict last.
validate 3 "$WORK/faults.pcap" "$WORK/clean.pcap" "$WORK/text.pcap"
grep -qE "^capture verdict: FAIL - [1-9][0-9]* errors?, .*\($WORK/faults.pcap\)$" "$WORK/out" ||
  fail "faults: no capture verdict: $(grep verdict "$WORK/out")"
grep -qx "capture verdict: PASS - 0 errors, 0 warnings, 0 info ($WORK/clean.pcap)" "$WORK/out" ||
  fail "clean: no capture verdict: $(grep verdict "$WORK/out")"
grep -qx "capture verdict: UNREADABLE - $WORK/text.pcap: cannot read capture: unknown file format" "$WORK/out" ||
  fail "unreadable: no capture verdict: $(grep verdict "$WORK/out")"
tail -1 "$WORK/out" | grep -q "^verdict: FAIL - .* in 3 captures, 1 unreadable (exit 3: a capture could not be read to its end)$" ||
  fail "overall verdict not last: $(tail -1 "$WORK/out")"
validate 4 --config "$WORK/ghost.toml" "$WORK/clean.pcap"
grep -qx "capture verdict: NO SERVO - 0 errors, 0 warnings, 0 info ($WORK/clean.pcap)" "$WORK/out" ||
  fail "no servo: no capture verdict: $(grep verdict "$WORK/out")"

# One line per rule and axis, with the count, first and last frame; --verbose lists each finding.
validate 0 --fail-on never --format json "$WORK/lossy.pcap"
cp "$WORK/out" "$WORK/lossy.json"
validate 0 --fail-on never "$WORK/lossy.pcap"
cp "$WORK/out" "$WORK/lossy.txt"
validate 0 --fail-on never --verbose "$WORK/lossy.pcap"
cp "$WORK/out" "$WORK/lossy-verbose.txt"
python3 - "$WORK" <<'PY' || fail "grouped text lines"
import json, re, sys
w = sys.argv[1]
findings = json.load(open(f"{w}/lossy.json"))["captures"][0]["findings"]
com4 = [f for f in findings if f["rule"] == "COM-004"]
assert len(com4) > 10, len(com4)
text = open(f"{w}/lossy.txt").read().splitlines()
lines = [l for l in text if re.match(r"^(error|warning|info) +[A-Z]+-\d{3} ", l)]
groups = {(f["rule"], f["axis_name"] or "bus") for f in findings}
assert len(lines) == len(groups), (lines, groups)
line = next(l for l in lines if " COM-004 " in l)
day = lambda f: f["time_utc"][11:23]  # the time of day to the millisecond, UTC
want = (f"warning COM-004 bus {len(com4)} findings, frames {com4[0]['frame']} ({com4[0]['time']:.6f} s, {day(com4[0])}) "
        f"to {com4[-1]['frame']} ({com4[-1]['time']:.6f} s, {day(com4[-1])}), first: {com4[0]['message']}")
assert line == want, (line, want)
verbose = [l for l in open(f"{w}/lossy-verbose.txt").read().splitlines()
           if re.match(r"^(error|warning|info) +[A-Z]+-\d{3} ", l)]
assert len(verbose) == len(findings), (len(verbose), len(findings))
assert all(" frame " in l and "findings," not in l for l in verbose), verbose[:2]
assert [l for l in text if l.startswith("capture verdict:")] == \
    [l for l in open(f"{w}/lossy-verbose.txt").read().splitlines() if l.startswith("capture verdict:")]
PY

# Configured axis names in every format (the axis index stays `axis` in JSON).
for format in text json jsonl junit sarif; do
  validate 1 --config "$WORK/named.toml" --format "$format" "$WORK/faults.pcap"
  cp "$WORK/out" "$WORK/named.$format"
done
python3 - "$WORK" <<'PY' || fail "axis names"
import json, re, sys, xml.etree.ElementTree as ET
w = sys.argv[1]
names = {0: "X", 1: "Y", 2: "Z", 3: "W"}
cap = json.load(open(f"{w}/named.json"))["captures"][0]
axis_findings = [f for f in cap["findings"] if f["axis"] is not None]
assert axis_findings
for f in cap["findings"]:
    assert f["axis_name"] == (names[f["axis"]] if f["axis"] is not None else None), f
for l in open(f"{w}/named.jsonl"):
    f = json.loads(l)
    if "rule" in f:
        assert f["axis_name"] == (names[f["axis"]] if f["axis"] is not None else None), f
text = open(f"{w}/named.text").read()
assert "axis0" not in text and "axis1" not in text, [l for l in text.splitlines() if "axis0" in l][:3]
for f in axis_findings:
    assert re.search(rf"^\S+ +{f['rule']} +{names[f['axis']]} ", text, re.M), f
for r in json.load(open(f"{w}/named.sarif"))["runs"][0]["results"]:
    if r["properties"]["axis"] is not None:
        assert r["properties"]["axis_name"] == names[r["properties"]["axis"]], r
        # A finding's message is "AXIS frame N: ...", an incident's "AXIS fault E09 at frame N".
        after = " " if r["ruleId"].startswith("INC-") else " frame "
        assert r["message"]["text"].startswith(names[r["properties"]["axis"]] + after), r
junit = open(f"{w}/named.junit").read()
assert "axis0" not in junit and " X [" in junit, junit[:400]
PY

# time_utc beside every time: the capture's own clock in UTC, with its precision.
validate 0 --fail-on never --format json "$WORK/faults.pcap" "$WORK/nano.pcapng" "$WORK/nano.pcapng.gz"
python3 - "$WORK" <<'PY' || fail "time_utc"
import datetime, json, struct, sys
w = sys.argv[1]
def first_time(path):  # the first record's time, read here from the file itself
    data = open(path, "rb").read()
    if data[:4] == b"\x0a\x0d\x0d\x0a":
        at = struct.unpack_from("<I", data, 4)[0]
        while struct.unpack_from("<I", data, at)[0] != 6:
            at += struct.unpack_from("<I", data, at + 4)[0]
        hi, lo = struct.unpack_from("<II", data, at + 12)
        return (hi << 32 | lo), 9  # the simulator's pcapng: if_tsresol 9
    sec, usec = struct.unpack_from("<II", data, 24)
    return sec * 10**6 + usec, 6
caps = json.load(open(f"{w}/out"))["captures"]
for cap, path in zip(caps, ["faults.pcap", "nano.pcapng", "nano.pcapng"]):
    start, digits = first_time(f"{w}/{path}")
    def check(obj):
        assert "time_utc" in obj, obj
        stamp = obj["time_utc"]
        assert stamp.endswith("Z") and len(stamp.split(".")[1]) == digits + 1, (stamp, digits)
        whole, frac = stamp[:-1].split(".")
        t = datetime.datetime.strptime(whole, "%Y-%m-%dT%H:%M:%S").replace(tzinfo=datetime.timezone.utc)
        ticks = int(t.timestamp()) * 10**digits + int(frac)
        assert abs(ticks - start - round(obj["time"] * 10**digits)) <= 1, (stamp, obj["time"], start)
    assert cap["findings"]
    for f in cap["findings"]:
        check(f)
    for a in cap["axes"]:
        for s in a["state_timeline"]:
            check(s)
        for e in a["error_history"]:
            check(e)
PY

# Several reports in one run: each the same as that format alone; no temporary file left.
mkdir "$WORK/reports"
validate 1 --config "$WORK/named.toml" --format text -o "$WORK/reports/r.txt" \
  --report json:"$WORK/reports/r.json" --report jsonl:"$WORK/reports/r.jsonl" \
  --report junit:"$WORK/reports/r.xml" --report sarif:"$WORK/reports/r.sarif" "$WORK/faults.pcap"
[ ! -s "$WORK/out" ] || fail "--output and --report: stdout not empty"
for pair in text:txt json:json jsonl:jsonl junit:xml sarif:sarif; do
  format=${pair%%:*} ext=${pair##*:}
  validate 1 --config "$WORK/named.toml" --format "$format" "$WORK/faults.pcap"
  cmp -s "$WORK/out" "$WORK/reports/r.$ext" || fail "--report $format differs from --format $format"
done
[ "$(ls -A "$WORK/reports" | wc -l)" = 5 ] || fail "files left beside the reports: $(ls -A "$WORK/reports")"
touch "$WORK/new"
[ "$(stat -c %a "$WORK/reports/r.json")" = "$(stat -c %a "$WORK/new")" ] ||
  fail "report mode $(stat -c %a "$WORK/reports/r.json"), a new file's $(stat -c %a "$WORK/new")"
# --report beside the text on standard output.
validate 1 --report sarif:"$WORK/reports/s.sarif" "$WORK/faults.pcap"
grep -q "^verdict: FAIL" "$WORK/out" || fail "--report: no text on stdout"
[ -s "$WORK/reports/s.sarif" ] || fail "--report sarif not written"

# Usage errors (exit 2, nothing written): a report over an input, two reports to one file.
cp "$WORK/faults.pcap" "$WORK/input.pcap"
ln -s "$WORK/input.pcap" "$WORK/alias.pcap"
before=$(sha256sum <"$WORK/input.pcap")
for args in "--report json:$WORK/input.pcap" "--report sarif:$WORK/./input.pcap" \
  "--report junit:$WORK/alias.pcap" "-o $WORK/r1 --report json:$WORK/r1" \
  "--report json:$WORK/r2 --report sarif:$WORK/./r2" "--report xml:$WORK/r3" "--report json" \
  "--report json:-"; do
  # shellcheck disable=SC2086
  validate 2 $args "$WORK/input.pcap"
  [ ! -s "$WORK/out" ] || fail "$args: wrote a report"
  [ -s "$WORK/err" ] || fail "$args: no message"
done
grep -q "standard output has the --format report" "$WORK/err" || fail "--report json:-: $(cat "$WORK/err")"
[ "$(sha256sum <"$WORK/input.pcap")" = "$before" ] || fail "a report wrote over its input"
for f in r1 r2 r3; do [ ! -e "$WORK/$f" ] || fail "$f written by a refused run"; done

# An interrupted run leaves no half report: the old report stays, no temporary file remains.
# (SIGTERM: a background job of a script ignores SIGINT, and validate leaves it ignored.)
echo "old report" >"$WORK/reports/long.json"
mkfifo "$WORK/pipe"
"$NCSERVO" validate --format json -o "$WORK/reports/long.json" --report sarif:"$WORK/reports/long.sarif" \
  - <"$WORK/pipe" >/dev/null 2>&1 &
exec 3>"$WORK/pipe"
head -c 30000 "$WORK/faults.pcap" >&3  # part of a capture; the rest never comes
sleep 1
ls -A "$WORK/reports" | grep -q '^\.long\.json\.' || fail "no temporary report while running: $(ls -A "$WORK/reports")"
kill -TERM $! || fail "validate ended before it was interrupted"
wait $! 2>/dev/null || true
exec 3>&-
[ "$(cat "$WORK/reports/long.json")" = "old report" ] || fail "interrupted run replaced the report"
[ ! -e "$WORK/reports/long.sarif" ] || fail "interrupted run wrote a report"
ls -A "$WORK/reports" | grep -q '^\.' && fail "temporary files left: $(ls -A "$WORK/reports")"

# JUnit: disabled rules and captures with nothing checked are skipped.
validate 3 --format junit "$WORK/faults.pcap" "$WORK/text.pcap" --disable MSG-001,SE-002
cp "$WORK/out" "$WORK/skipped.xml"
validate 4 --format junit --config "$WORK/ghost.toml" "$WORK/clean.pcap"
cp "$WORK/out" "$WORK/noservo.xml"
RULE_COUNT=$(grep -c '^| <a id=' "$SRC/docs/rules.md") python3 - "$WORK" <<'PY' || fail "junit skipped"
import os, sys, xml.etree.ElementTree as ET
w = sys.argv[1]
rule_count = int(os.environ["RULE_COUNT"])  # docs/rules.md's rows (docs_generated: the table's)
suites = ET.parse(f"{w}/skipped.xml").getroot()
faults, text = suites
def case(suite, rule):
    return next(c for c in suite if c.get("name", "").startswith(rule + " "))
for rule in ("MSG-001", "SE-002"):
    c = case(faults, rule)
    assert c.find("skipped") is not None and "disabled" in c.find("skipped").text, ET.tostring(c)
assert case(faults, "SE-001").find("skipped") is None
for rule in ("COM-006", "COM-007"):  # off by default
    assert "off by default" in case(faults, rule).find("skipped").text, ET.tostring(case(faults, rule))
assert faults.get("skipped") == "4", faults.attrib
rules = [c for c in text if c.get("name") != "capture readable"]
assert len(rules) == rule_count and all(c.find("skipped") is not None for c in rules), ET.tostring(text)[:300]
assert all(c.find("skipped").text.startswith(("UNREADABLE", "disabled", "off by default")) for c in rules)
assert text.get("errors") == "1" and text.get("skipped") == str(rule_count), text.attrib
noservo = ET.parse(f"{w}/noservo.xml").getroot()[0]
assert noservo.get("skipped") == str(rule_count), noservo.attrib
assert all(c.find("skipped").text.startswith(("NO SERVO", "off by default")) for c in noservo), ET.tostring(noservo)[:300]
PY

# SARIF: notifications for an unreadable capture and for NO SERVO; results located by frame, with
# the frame's record in a plain file (none in a compressed one), rule indexes and help anchors.
validate 3 --format sarif "$WORK/faults.pcap" "$WORK/nano.pcapng" "$WORK/nano.pcapng.gz" \
  "$WORK/text.pcap" "$WORK/clean.pcap" --config "$WORK/ghost.toml"
cp "$WORK/out" "$WORK/notes.sarif"
validate 1 --format sarif "$WORK/faults.pcap" "$WORK/nano.pcapng" "$WORK/nano.pcapng.gz"
cp "$WORK/out" "$WORK/located.sarif"
python3 - "$WORK" "$SRC/docs/rules.md" "$SRC/docs/incidents.md" <<'PY' || fail "sarif"
import json, re, struct, sys, urllib.parse
w, rules_md, incidents_md = sys.argv[1], open(sys.argv[2]).read(), open(sys.argv[3]).read()
# The cause ids of docs/incidents.md's table, in its order.
cause_ids = re.findall(r"^\| `([a-z-]+)` \|", incidents_md.split("## Causes")[1].split("\n## ")[0], re.M)
def path_of(uri):  # the captures were named by absolute paths: file: URIs
    assert uri.startswith("file:///"), uri
    return urllib.parse.unquote(urllib.parse.urlparse(uri).path)
def records(path):  # frame number -> (offset, length) of its record, read here independently
    data, out = open(path, "rb").read(), {}
    if data[:4] == b"\x0a\x0d\x0d\x0a":
        at = 0
        while at < len(data):
            kind, length = struct.unpack_from("<II", data, at)
            if kind in (3, 6):
                out[len(out) + 1] = (at, length)
            at += length
    else:
        at = 24
        while at < len(data):
            caplen = struct.unpack_from("<I", data, at + 8)[0]
            out[len(out) + 1] = (at, 16 + caplen)
            at += 16 + caplen
    return out
run = json.load(open(f"{w}/located.sarif"))["runs"][0]
rules = run["tool"]["driver"]["rules"]
assert run["invocations"] == [{"executionSuccessful": True}], run["invocations"]
catalogue = [rule for rule in rules if not rule["id"].startswith("INC-")]
causes = [rule["id"] for rule in rules if rule["id"].startswith("INC-")]
# After the catalogue, a rule per incident cause (docs/incidents.md#causes).
assert rules[:len(catalogue)] == catalogue and causes == ["INC-" + c for c in cause_ids], causes
assert all(r["helpUri"].endswith("/docs/incidents.md#causes") for r in rules[len(catalogue):])
for rule in catalogue:
    anchor = rule["helpUri"].split("#")[1]
    assert rule["helpUri"].endswith("/docs/rules.md#" + anchor) and anchor == rule["id"].lower()
    assert f'<a id="{anchor}"></a>{rule["id"]} |' in rules_md, anchor
located = {}
for r in run["results"]:
    assert rules[r["ruleIndex"]]["id"] == r["ruleId"], r
    loc = r["locations"][0]
    frame = r["properties"]["frame"]
    assert loc["logicalLocations"][0]["name"] == f"frame {frame}", loc
    uri = path_of(loc["physicalLocation"]["artifactLocation"]["uri"])
    # GitHub's code scanning takes no location without a startLine: line 1, as a capture has none.
    assert loc["physicalLocation"]["region"] == {"startLine": 1}, loc
    related = r.get("relatedLocations")
    if uri.endswith(".gz"):
        assert related is None, r
        continue
    assert path_of(related[0]["physicalLocation"]["artifactLocation"]["uri"]) == uri, related
    region = related[0]["physicalLocation"]["region"]
    got = (region["byteOffset"], region["byteLength"])
    want = records(uri)[frame]
    assert got == want, (uri, frame, got, want)
    located[uri] = located.get(uri, 0) + 1
assert len(located) == 2 and all(located.values()), located
keys = [r["partialFingerprints"]["ncservoFinding/v1"] for r in run["results"]
        if not r["ruleId"].startswith("INC-")]
assert all(re.match(r"^[A-Z]+-\d{3}:[^:]+:\d+$", k) for k in keys), keys[:3]
incidents = [r for r in run["results"] if r["ruleId"].startswith("INC-")]
assert incidents and all(
    re.match(r"^(drive-fault|bus-outage|esm) \S+ [a-z-]+ #\d+$",
             r["partialFingerprints"]["ncservoIncident/v1"]) for r in incidents), incidents[:1]
notes_run = json.load(open(f"{w}/notes.sarif"))["runs"][0]
inv = notes_run["invocations"][0]
assert inv["executionSuccessful"] is False, inv
notes = [(n["descriptor"]["id"],
          path_of(n["locations"][0]["physicalLocation"]["artifactLocation"]["uri"]))
         for n in inv["toolExecutionNotifications"]]
assert ("UNREADABLE", f"{w}/text.pcap") in notes, notes
assert ("NO-SERVO", f"{w}/clean.pcap") in notes, notes
PY
# The same run twice gives the same fingerprints.
validate 1 --format sarif "$WORK/faults.pcap" "$WORK/nano.pcapng" "$WORK/nano.pcapng.gz"
cmp -s "$WORK/out" "$WORK/located.sarif" || fail "SARIF differs between two runs"

# A report to a pipe or a device is written into it, never renamed over it (as root, renaming
# over /dev/null would replace the device); through a link, the file it names gets the report.
mkfifo "$WORK/report-pipe"
timeout 30 cat "$WORK/report-pipe" >"$WORK/from-pipe" &
reader=$!
"$NCSERVO" validate --format json -o "$WORK/report-pipe" --fail-on never "$SRC/captures/faults-4axis.pcap" ||
  fail "report to a FIFO: exit $?"
wait "$reader" || true
[ -p "$WORK/report-pipe" ] || fail "the FIFO was replaced by the report"
python3 -c 'import json,sys; json.load(open(sys.argv[1]))' "$WORK/from-pipe" || fail "no report through the FIFO"
"$NCSERVO" validate --format json -o /dev/null --fail-on never "$SRC/captures/faults-4axis.pcap" ||
  fail "report to /dev/null: exit $?"
[ -c /dev/null ] || fail "/dev/null is no longer a device"
: >"$WORK/real.json"
ln -s real.json "$WORK/link.json"
"$NCSERVO" validate --format json -o "$WORK/link.json" --fail-on never "$SRC/captures/faults-4axis.pcap" ||
  fail "report through a link: exit $?"
[ -L "$WORK/link.json" ] || fail "the link was replaced by the report"
[ -s "$WORK/real.json" ] || fail "the file the link names did not get the report"

echo "reports: verdict per capture, grouped findings, axis names, time_utc, --report, JUnit, SARIF"
