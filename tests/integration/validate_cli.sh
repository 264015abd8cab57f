#!/usr/bin/env bash
# validate_cli.sh SRC BUILD
# `ncservo validate`: every exit code of docs/cli.md, the five formats parse and agree, several
# captures and standard input, overrides from the command line and the config file, and a damaged
# capture still reports what came before the damage.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

run() {  # run EXPECTED_RC ARGS...: runs ncservo validate, checks the exit status
  local expected=$1
  shift
  set +e
  "$NCSERVO" validate "$@" >"$WORK/out" 2>"$WORK/err"
  local rc=$?
  set -e
  [ "$rc" = "$expected" ] || fail "validate $*: exit $rc, expected $expected; stderr: $(head -3 "$WORK/err")"
}

python3 "$GEN" --axes 2 --cycles 600 -o "$WORK/clean.pcap"
python3 "$GEN" --axes 2 --cycles 600 --inject SE-001@0.2:0 --inject MSG-001@0.4:1 -o "$WORK/faults.pcap" \
  --findings "$WORK/faults.expected.json"

# Exit codes: 0 clean, 1 findings at or above --fail-on, 0 below it or with never.
run 0 "$WORK/clean.pcap"
grep -q "^verdict: PASS" "$WORK/out" || fail "clean verdict: $(tail -1 "$WORK/out")"
run 1 "$WORK/faults.pcap"
grep -q "^verdict: FAIL - 1 error, 1 warning" "$WORK/out" || fail "faults verdict: $(tail -1 "$WORK/out")"
grep -q "^error   SE-001  axis0 1 finding, frame" "$WORK/out" || fail "text finding line: $(grep SE-001 "$WORK/out")"
run 1 --verbose "$WORK/faults.pcap"
grep -q "^error   SE-001  axis0 frame" "$WORK/out" || fail "text finding line: $(grep SE-001 "$WORK/out")"
run 0 --fail-on never "$WORK/faults.pcap"
run 0 --disable SE-001 "$WORK/faults.pcap"
run 1 --disable SE-001 --fail-on warning "$WORK/faults.pcap"
run 0 --severity SE-001=info "$WORK/faults.pcap"
run 1 --severity SE-001=info --fail-on info "$WORK/faults.pcap"
# Usage errors: 2, and nothing runs.
run 2 --disable XX-999 "$WORK/faults.pcap"
grep -q "XX-999" "$WORK/err" || fail "unknown rule not named: $(cat "$WORK/err")"
run 2 --timeout no_such=5 "$WORK/faults.pcap"
run 2 --timeout drive_response=abc "$WORK/faults.pcap"
run 2 --format xml "$WORK/faults.pcap"
run 2 --servo-ready-mode 2 "$WORK/faults.pcap"
printf 'telegram_failure_limit = 3\n[rules]\ndisable = ["SE-001", "NOPE-1"]\n' >"$WORK/bad.toml"
run 2 --config "$WORK/bad.toml" "$WORK/faults.pcap"
grep -q "bad.toml:3: key 'rules.disable'" "$WORK/err" || fail "config error: $(cat "$WORK/err")"
[ ! -s "$WORK/out" ] || fail "a bad config must stop before any output"
printf '[rules]\ndisable = ["SE-001"]\n[timeouts]\ndrive_response = 30\n' >"$WORK/good.toml"
run 0 --config "$WORK/good.toml" "$WORK/faults.pcap"

# Capture errors: 3, naming the file; what was read before the damage is still reported.
run 3 "$WORK/missing.pcap"
grep -qF "$WORK/missing.pcap" "$WORK/err" || fail "missing file not named"
echo "not a capture" >"$WORK/text.pcap"
run 3 "$WORK/text.pcap"
grep -qF "$WORK/text.pcap" "$WORK/err" || fail "non-capture not named"
size=$(stat -c %s "$WORK/faults.pcap")
head -c $((size * 3 / 4)) "$WORK/faults.pcap" >"$WORK/cut.pcap"
run 3 --format json "$WORK/cut.pcap"
grep -qE "cut.pcap: frame [0-9]+" "$WORK/err" || fail "truncation message: $(cat "$WORK/err")"
python3 - "$WORK/out" <<'PY' || fail "cut capture JSON"
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]
assert "error" in c and "frame" in c["error"], c.get("error")
assert any(f["rule"] == "SE-001" for f in c["findings"]), "findings before the damage lost"
PY
# The text verdict says a capture was not read to its end, beside what was found before it.
run 3 "$WORK/cut.pcap" "$WORK/clean.pcap"
grep -qE "^verdict: FAIL - [1-9][0-9]* errors?, .* in 2 captures, 1 not read to the end \(exit 3: a capture could not be read to its end\)$" \
  "$WORK/out" || fail "cut capture verdict: $(tail -1 "$WORK/out")"

# Several captures: the most serious status in the order 2, 3, 1, 0.
run 3 "$WORK/faults.pcap" "$WORK/missing.pcap" "$WORK/clean.pcap"
run 1 "$WORK/clean.pcap" "$WORK/faults.pcap"
grep -q " in 2 captures (exit 1: findings at or above --fail-on error)$" "$WORK/out" ||
  fail "two captures: $(tail -1 "$WORK/out")"

# Standard input, and --output.
"$NCSERVO" validate --format jsonl - <"$WORK/faults.pcap" >"$WORK/stdin.jsonl" && fail "stdin: expected exit 1"
[ "$(grep -c '"rule"' "$WORK/stdin.jsonl")" = 2 ] || fail "stdin jsonl: $(cat "$WORK/stdin.jsonl")"
run 1 --format json --output "$WORK/report.json" "$WORK/faults.pcap"
[ ! -s "$WORK/out" ] || fail "--output: stdout not empty"

# The catalogue's size, from docs/rules.md (docs_generated holds it to the rule table).
RULE_COUNT=$(grep -c '^| <a id=' "$SRC/docs/rules.md")
# docs/incidents.md's cause table (a unit test holds it to the library's).
CAUSE_COUNT=$(sed -n '/^## Causes/,/^## /p' "$SRC/docs/incidents.md" | grep -c '^| `')
export RULE_COUNT CAUSE_COUNT
# The formats agree on the findings.
for format in json jsonl junit sarif text; do
  run 1 --format "$format" "$WORK/faults.pcap" "$WORK/clean.pcap"
  cp "$WORK/out" "$WORK/report.$format"
done
python3 - "$WORK" <<'PY' || fail "formats disagree"
import json, os, sys, xml.etree.ElementTree as ET
w = sys.argv[1]
rule_count = int(os.environ["RULE_COUNT"])
doc = json.load(open(f"{w}/report.json"))
assert doc["tool"]["name"] == "ncservo"
caps = doc["captures"]
assert [len(c["findings"]) for c in caps] == [2, 0], caps
c = caps[0]
for key in ("path", "frames", "cycles", "cycle_time_us", "layout", "findings", "axes", "summary"):
    assert key in c, key
assert c["frames"] == 1200 and c["cycles"] == 600, (c["frames"], c["cycles"])
assert c["cycle_time_us"]["median"] == 1000.0
assert c["layout"]["source"] == "inferred" and len(c["layout"]["axes"]) == 2
assert c["layout"]["axes"][1]["outputs"] == "0x0001000A", c["layout"]["axes"][1]
assert c["summary"] == {"error": 1, "warning": 1, "info": 0}, c["summary"]
want = sorted((f["rule"], f["axis"], f["frame"]) for f in c["findings"])
for f in c["findings"]:
    assert set(f) == {"rule", "slug", "severity", "axis", "axis_name", "frame", "since_frame", "time",
                      "time_utc", "message", "fingerprint"}, f
    assert f["message"]
for a in c["axes"]:
    assert {"index", "name", "state", "state_timeline", "error_history", "telegram_failures"} <= set(a)
    assert any(s["transition"] == "ENABLE OPERATION" for s in a["state_timeline"]), a["state_timeline"][:4]
lines = [l for l in map(json.loads, open(f"{w}/report.jsonl")) if "rule" in l]
assert sorted((l["rule"], l["axis"], l["frame"]) for l in lines) == want, lines
sarif = json.load(open(f"{w}/report.sarif"))
assert sarif["version"] == "2.1.0"
run = sarif["runs"][0]
# The rule table, then a rule per incident cause (INC-…).
assert len(run["tool"]["driver"]["rules"]) == rule_count + int(os.environ["CAUSE_COUNT"])
res = [r for r in run["results"] if not r["ruleId"].startswith("INC-")]
assert len(res) + sum(len(c["incidents"]) for c in caps) == len(run["results"])
assert sorted((r["ruleId"], r["properties"]["axis"], r["properties"]["frame"]) for r in res) == want
assert all(r["locations"] and r["locations"][0]["physicalLocation"]["artifactLocation"]["uri"] for r in res)
suites = ET.parse(f"{w}/report.junit").getroot()
assert suites.tag == "testsuites" and len(suites) == 2
s0 = suites[0]
# A case per rule and per incident; MSG-001 is a warning, and incidents gate only when asked.
assert s0.get("tests") == str(rule_count + len(c["incidents"])) and s0.get("failures") == "1", s0.attrib
failed = [tc.get("name") for tc in s0 if tc.find("failure") is not None]
assert failed == ["SE-001 illegal-enable-edge"], failed
assert suites[1].get("failures") == "0"
text = open(f"{w}/report.text").read()
assert "== " in text and "verdict: FAIL" in text
PY

# `rules` lists the whole catalogue.
"$NCSERVO" rules >"$WORK/rules.txt"
[ "$(wc -l <"$WORK/rules.txt")" = "$RULE_COUNT" ] || fail "rules: $(wc -l <"$WORK/rules.txt") lines"
"$NCSERVO" validate --help | grep -q -- "--fail-on" || fail "validate --help"
# An output that is one of the inputs, under any name, is a usage error and the capture is intact.
cp "$SRC/captures/faults-4axis.pcap" "$WORK/input.pcap"
ln -s "$WORK/input.pcap" "$WORK/alias.pcap"
before=$(sha256sum <"$WORK/input.pcap")
for output in "$WORK/input.pcap" "$WORK/./input.pcap" "$WORK/alias.pcap"; do
  set +e
  "$NCSERVO" validate -o "$output" "$SRC/captures/commissioning-4axis.pcap" "$WORK/input.pcap" \
    2>"$WORK/over.err"
  rc=$?
  set -e
  [ $rc = 2 ] || fail "validate -o $output over its input: exit $rc, expected 2"
  grep -q "refusing to write over an input" "$WORK/over.err" || fail "no message: $(cat "$WORK/over.err")"
  [ "$(sha256sum <"$WORK/input.pcap")" = "$before" ] || fail "validate -o $output wrote over its input"
done

# Verdict words describe the capture (docs/cli.md#verdicts): --fail-on never over errors exits 0,
# and neither the text nor the HTML says PASS; the last line says why the status is 0.
faults4="$SRC/captures/faults-4axis.pcap"
run 0 --fail-on never --report html:"$WORK/never.html" --report json:"$WORK/never.json" "$faults4"
! grep -q PASS "$WORK/out" || fail "--fail-on never: PASS in the text: $(grep PASS "$WORK/out")"
! grep -q PASS "$WORK/never.html" || fail "--fail-on never: PASS in the HTML"
grep -q '"verdict":"fail"' "$WORK/never.html" || fail "--fail-on never: the HTML's verdict is not fail"
grep -q "^capture verdict: FAIL - 5 errors" "$WORK/out" || fail "capture verdict: $(grep 'capture verdict' "$WORK/out")"
tail -1 "$WORK/out" | grep -q "^verdict: FAIL - 5 errors, .* (exit 0: --fail-on never)$" ||
  fail "last line: $(tail -1 "$WORK/out")"
# Warnings only: WARN, exit 0 under the default --fail-on, FAIL with --fail-on warning (stricter).
run 0 "$WORK/clean.pcap" --severity SE-001=warning "$WORK/faults.pcap"
grep -q "^capture verdict: WARN - 0 errors, 2 warnings, 0 info ($WORK/faults.pcap)$" "$WORK/out" ||
  fail "warnings only: $(grep 'capture verdict' "$WORK/out")"
# (Each capture's drive fault is an incident, which gates only when asked: docs/cli.md#exit-status.)
tail -1 "$WORK/out" | grep -q "^verdict: WARN - .*(exit 0: nothing at or above --fail-on error, 2 incidents not gated (--fail-on-incident never))$" ||
  fail "warnings only, last line: $(tail -1 "$WORK/out")"
run 1 --fail-on warning --severity SE-001=warning "$WORK/faults.pcap"
grep -q "^capture verdict: FAIL - 0 errors, 2 warnings" "$WORK/out" || fail "--fail-on warning: $(tail -2 "$WORK/out")"
tail -1 "$WORK/out" | grep -q "(exit 1: findings at or above --fail-on warning)$" || fail "$(tail -1 "$WORK/out")"
run 0 --format json --severity SE-001=warning "$WORK/faults.pcap"
grep -q '"verdict": "warn"' "$WORK/out" || fail "JSON verdict of warnings: $(grep verdict "$WORK/out")"

# Error codes are named (the field table's bit names): "E19 I2t_Endat" in text, JSON and HTML.
run 0 --fail-on never "$faults4"
grep -q "^    error E19 I2t_Endat (0x4200) at frame 2402" "$WORK/out" || fail "text: no named error code"
python3 - "$WORK/never.json" <<'PY' || fail "JSON: error codes not named"
import json, sys
history = [e for a in json.load(open(sys.argv[1]))["captures"][0]["axes"] for e in a["error_history"]]
assert {(e["code"], e["name"], e["canopen"]) for e in history} >= {("E19", "I2t_Endat", "0x4200"),
                                                                   ("E09", "FollowerErr", "0x8611")}, history
PY
grep -q '"E19 I2t_Endat"' "$WORK/never.html" || fail "HTML: error codes not named"

# A capture that cannot be read at all: one UNREADABLE line with the reason and nothing else, the
# run's line counts it once, JSON and JSON Lines give the reason.
mkdir "$WORK/directory"
: >"$WORK/empty.pcap"
for bad in missing.pcap directory empty.pcap; do
  run 3 "$WORK/$bad"
  [ "$(grep -vc '^== ' "$WORK/out")" = 2 ] || fail "$bad: more than its verdict lines: $(cat "$WORK/out")"
  grep -q "^capture verdict: UNREADABLE - $WORK/$bad: cannot read capture: " "$WORK/out" ||
    fail "$bad: $(cat "$WORK/out")"
  tail -1 "$WORK/out" | grep -q " in 1 capture, 1 unreadable (exit 3: " || fail "$bad: $(tail -1 "$WORK/out")"
  ! grep -q "NO SERVO\|0 frames\|no servo" "$WORK/out" || fail "$bad: half a report: $(cat "$WORK/out")"
  run 3 --format json "$WORK/$bad"
  python3 -c 'import json,sys; c=json.load(open(sys.argv[1]))["captures"][0]; assert c["verdict"] == "unreadable" and c["reason"] and "layout" not in c, c' \
    "$WORK/out" || fail "$bad: JSON"
  run 3 --format jsonl "$WORK/$bad"
  [ "$(wc -l <"$WORK/out")" = 1 ] && grep -q '"verdict":"unreadable","reason":"' "$WORK/out" ||
    fail "$bad: JSON Lines: $(cat "$WORK/out")"
done

echo "validate_cli: exit codes, formats, several captures, stdin, overrides, verdict words, named error codes, unreadable captures"
