#!/usr/bin/env bash
# baseline.sh SRC BUILD: `validate --baseline` and `ncservo diff` (docs/baselines.md). A simulated
# capture with faults is the baseline; the same recording behind another one (mergecap -a) matches
# it in full (0 new, exit 0); a copy with one more violation of another rule has exactly that one
# new (exit 1, in text, JSON, JSON Lines, JUnit and SARIF's baselineState), and `diff` names it;
# a capture against itself is no difference. SARIF and JUnit with a baseline are checked against
# their schemas last; without them the test skips (77, saying why; under CI it fails). A third
# argument --no-schemas (the sanitizer build) leaves that check to the plain build, saying so.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
MERGECAP=${MERGECAP:-mergecap}
command -v "$MERGECAP" >/dev/null || fail "mergecap not found"

# The same seed and faults, and one more fault of a rule and axis not already there (SEW-001, an
# error, on axis1).
faults=(--scenario commissioning --seed 3 --fault SE-002@0.7:0 --fault COM-002@0.9
        --fault EC-001@1.0:2)
"$NCSERVO" simulate "${faults[@]}" -o "$WORK/base.pcap" 2>/dev/null
"$NCSERVO" simulate "${faults[@]}" --fault SEW-001@1.2:1 -o "$WORK/more.pcap" 2>/dev/null
"$NCSERVO" simulate --scenario commissioning --seed 9 -o "$WORK/other.pcap" 2>/dev/null
"$MERGECAP" -a -w "$WORK/behind.pcap" "$WORK/other.pcap" "$WORK/base.pcap"
"$MERGECAP" -a -w "$WORK/twice.pcap" "$WORK/base.pcap" "$WORK/base.pcap"
cd "$WORK"

rc=0
"$NCSERVO" validate --format json -o base.json base.pcap || rc=$?
[ "$rc" = 1 ] || fail "the baseline capture exits $rc, expected 1 (it has errors)"
python3 - base.json <<'PY' || fail "the baseline's findings have no fingerprints"
import json, sys
findings = json.load(open(sys.argv[1]))["captures"][0]["findings"]
assert len(findings) == 3, findings
for f in findings:
    assert f["fingerprint"] == f'{f["rule"]} {f["axis_name"] or "bus"} #1', f
PY

# json_counts REPORT: "NEW UNCHANGED ABSENT" of the first capture, and each finding's state.
json_counts() {
  python3 - "$1" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]
b = c["baseline"]
states = [f["baseline"] for f in c["findings"]]
assert states.count("new") == b["new"] and states.count("unchanged") == b["unchanged"], c
assert len(c["baseline_absent"]) == b["absent"]
print(b["new"], b["unchanged"], b["absent"], *[f["rule"] for f in c["findings"] if f["baseline"] == "new"])
PY
}

# The same recording behind another one, and the baseline itself: all unchanged, exit 0. (The
# recording in front has a drive fault of its own, the commissioning scenario's E09: one new
# incident, which incident_gate.sh judges; here only the findings are.)
for capture in behind base; do
  rc=0
  "$NCSERVO" validate --baseline base.json --fail-on-incident never --format json \
    -o "$capture.json" "$capture.pcap" || rc=$?
  [ "$rc" = 0 ] || fail "$capture against its baseline exits $rc, expected 0"
  counts=$(json_counts "$capture.json")
  [ "$counts" = "0 3 0" ] || fail "$capture against its baseline: '$counts', expected '0 3 0'"
done
# The text says it, and the verdict is about the new findings.
"$NCSERVO" validate --baseline base.json --fail-on-incident never behind.pcap >behind.txt 2>/dev/null ||
  fail "behind.pcap in text exits $?"
grep -q '^baseline: 0 new, 3 unchanged, 0 absent against base.json' behind.txt ||
  fail "no baseline line in the text: $(grep baseline behind.txt)"
tail -1 behind.txt | grep -q '^verdict: PASS - 0 new errors, .*against the baseline: 0 new, 3 unchanged, 0 absent' ||
  fail "the last line: $(tail -1 behind.txt)"

# The recording twice over: the second copy's segment has the same fingerprints, and its three
# findings are new (a fingerprint is taken once).
rc=0
"$NCSERVO" validate --baseline base.json --format json -o twice.json twice.pcap 2>/dev/null || rc=$?
[ "$rc" = 1 ] || fail "twice.pcap exits $rc, expected 1"
counts=$(json_counts twice.json)
[ "${counts%% [A-Z]*}" = "3 3 0" ] || fail "twice.pcap: '$counts', expected 3 new, 3 unchanged"

# One more violation: exactly that one new, exit 1; --fail-on never exits 0.
rc=0
"$NCSERVO" validate --baseline base.json --format json -o more.json \
  --report sarif:more.sarif --report junit:more.xml --report jsonl:more.jsonl more.pcap || rc=$?
[ "$rc" = 1 ] || fail "more.pcap exits $rc, expected 1"
counts=$(json_counts more.json)
[ "$counts" = "1 3 0 SEW-001" ] || fail "more.pcap: '$counts', expected '1 3 0 SEW-001'"
python3 - more.sarif <<'PY' || fail "SARIF baselineState disagrees"
import json, sys
results = json.load(open(sys.argv[1]))["runs"][0]["results"]
states = sorted((r["ruleId"], r["baselineState"]) for r in results)
assert states == [("COM-002", "unchanged"), ("EC-001", "unchanged"),
                  ("INC-communication-loss", "unchanged"), ("SE-002", "unchanged"),
                  ("SEW-001", "new")], states
PY
grep -c '"baseline":"new"' more.jsonl | grep -qx 1 || fail "JSON Lines: not one new finding"
grep -q '"baseline":{"report":"base.json","capture":"base.pcap","new":1,"unchanged":3,"absent":0' more.jsonl ||
  fail "JSON Lines: no counts line"
grep -q 'name="baseline" value="1 new, 3 unchanged, 0 absent' more.xml || fail "JUnit: no counts"
[ "$(grep -c '<failure' more.xml)" = 1 ] || fail "JUnit: not one failed test case (the new one)"
rc=0
"$NCSERVO" validate --baseline base.json --fail-on never more.pcap >/dev/null || rc=$?
[ "$rc" = 0 ] || fail "--fail-on never exits $rc"

# One fewer: the baseline taken from `more` holds SEW-001, which base.pcap lacks: absent.
"$NCSERVO" validate --format json -o more_base.json more.pcap >/dev/null 2>&1 || true
rc=0
"$NCSERVO" validate --baseline more_base.json --format json -o fewer.json --report sarif:fewer.sarif \
  base.pcap 2>/dev/null || rc=$?
[ "$rc" = 0 ] || fail "base.pcap against more's baseline exits $rc, expected 0"
[ "$(json_counts fewer.json)" = "0 3 1" ] || fail "one fewer: '$(json_counts fewer.json)'"
grep -q '"baselineState": "absent"' fewer.sarif || fail "SARIF: no absent result"

# A baseline that cannot be read is a usage error naming the file.
printf 'not json\n' >bad.json
for bad in bad.json missing.json; do
  rc=0
  "$NCSERVO" validate --baseline "$bad" base.pcap >/dev/null 2>err.txt || rc=$?
  [ "$rc" = 2 ] || fail "--baseline $bad exits $rc, expected 2"
  grep -q "$bad" err.txt || fail "--baseline $bad: the message does not name it: $(cat err.txt)"
done

# diff: the one more violation is named, exit 1; a capture against itself, or its report, exits 0.
rc=0
"$NCSERVO" diff base.pcap more.pcap >diff.txt || rc=$?
[ "$rc" = 1 ] || fail "diff base more exits $rc, expected 1"
grep -q '^findings: 1 new, 3 unchanged, 0 absent' diff.txt || fail "diff: $(head -3 diff.txt)"
grep -q '^new     error   SEW-001 axis1 #1' diff.txt || fail "diff does not name SEW-001: $(cat diff.txt)"
rc=0
"$NCSERVO" diff --format json base.json more.pcap >diff.json || rc=$?
[ "$rc" = 1 ] || fail "diff of a report and a capture exits $rc, expected 1"
python3 - diff.json <<'PY' || fail "diff JSON"
import json, sys
d = json.load(open(sys.argv[1]))
assert [f["rule"] for f in d["new"]] == ["SEW-001"] and d["absent"] == [], d
assert d["summary"] == {"new": 1, "unchanged": 3, "absent": 0}, d["summary"]
assert d["timing"]["cycle_us"]["base"]["p50"] == 1000.0, d["timing"]
PY
rc=0
"$NCSERVO" diff --format html -o diff.html base.pcap more.pcap || rc=$?
[ "$rc" = 1 ] && grep -q '<td>SEW-001</td>' diff.html && ! grep -q '<script' diff.html ||
  fail "diff html (exit $rc)"
for pair in "base.pcap base.pcap" "base.json base.pcap" "more.pcap base.pcap"; do
  rc=0
  "$NCSERVO" diff $pair >/dev/null || rc=$?
  [ "$rc" = 0 ] || fail "diff $pair exits $rc, expected 0"
done
rc=0
"$NCSERVO" diff --fail-on never base.pcap more.pcap >/dev/null || rc=$?
[ "$rc" = 0 ] || fail "diff --fail-on never exits $rc"
rc=0
"$NCSERVO" diff bad.json base.pcap >/dev/null 2>&1 || rc=$?
[ "$rc" = 3 ] || fail "diff of an unreadable report exits $rc, expected 3"
echo "baseline: behind another recording 0 new; one more violation 1 new (SARIF agrees); diff names it"

# The SARIF and JUnit with a baseline against their schemas, last: without the schemas (fetched by
# the fixture report_schemas_fetch, tests/integration/CMakeLists.txt) the test skips, saying so.
if [ "${3:-}" = --no-schemas ]; then
  echo "baseline: SARIF and JUnit not checked against their schemas here (--no-schemas: the plain build checks them)"
  exit 0
fi
schemas="$BUILD/schemas"
[ -s "$schemas/sarif-schema-2.1.0.json" ] && [ -s "$schemas/jenkins-junit.xsd" ] ||
  skip "no report schemas in $schemas (tests/tools/fetch_schemas.sh), SARIF and JUnit not checked; the rest passed"
python3 -c "import jsonschema" 2>/dev/null || skip "python3-jsonschema missing; the rest passed"
command -v xmllint >/dev/null || skip "xmllint missing; the rest passed"
for sarif in more.sarif fewer.sarif; do
  python3 - "$schemas/sarif-schema-2.1.0.json" "$sarif" <<'PY' || fail "$sarif: not valid SARIF 2.1.0"
import json, sys, jsonschema
schema = json.load(open(sys.argv[1]))
cls = jsonschema.validators.validator_for(schema)
errors = list(cls(schema).iter_errors(json.load(open(sys.argv[2]))))
for e in errors[:5]:
    print(list(e.path), e.message[:300], file=sys.stderr)
sys.exit(1 if errors else 0)
PY
done
xmllint --noout --schema "$schemas/jenkins-junit.xsd" more.xml 2>xmllint.err ||
  fail "more.xml: JUnit not valid: $(head -5 xmllint.err)"
echo "baseline: the SARIF and JUnit with a baseline are valid against their schemas"
