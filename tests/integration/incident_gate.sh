#!/usr/bin/env bash
# incident_gate.sh SRC BUILD: incidents gate CI (docs/cli.md#exit-status, docs/baselines.md).
# A commissioning recording (its own E09 on axis1, cleared) is the baseline; the same recording
# with one more drive fault before it (FLT-001's E09 on axis2) has exactly that incident new: validate
# --baseline and diff exit 1 by default, --fail-on-incident chooses the kinds, --fail-on never
# alone gates nothing; without a baseline incidents gate only when asked. JUnit has a test case
# per incident, SARIF a result of rule INC-<cause> with a region GitHub accepts (startLine).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
cd "$WORK"
recording=(--scenario commissioning --seed 3)
"$NCSERVO" simulate "${recording[@]}" -o base.pcap 2>/dev/null
"$NCSERVO" simulate "${recording[@]}" --fault FLT-001@0.7:2 -o more.pcap 2>/dev/null

# expect STATUS WHAT COMMAND...: runs the command, which must exit STATUS.
expect() {
  local want=$1 what=$2 rc=0
  shift 2
  "$@" >out.txt 2>err.txt || rc=$?
  [ "$rc" = "$want" ] || fail "$what: exit $rc, expected $want: $(tail -2 out.txt) $(cat err.txt)"
}

# Without a baseline an incident gates only when asked: the baseline recording passes.
expect 0 "the baseline recording" "$NCSERVO" validate --format json -o base.json base.pcap
python3 - base.json <<'PY' || fail "the baseline's incidents have no fingerprints"
import json, sys
incidents = json.load(open(sys.argv[1]))["captures"][0]["incidents"]
assert [i["fingerprint"] for i in incidents] == ["drive-fault axis1 following-error #1"], incidents
PY
expect 1 "an incident asked for" "$NCSERVO" validate --fail-on-incident drive-fault base.pcap
tail -1 out.txt | grep -q '(exit 1: 1 incident under --fail-on-incident drive-fault)$' ||
  fail "the reason: $(tail -1 out.txt)"
expect 0 "a kind not there" "$NCSERVO" validate --fail-on-incident bus-outage,esm base.pcap
expect 2 "a kind misspelt" "$NCSERVO" validate --fail-on-incident drive-faults base.pcap
grep -q "'drive-faults' is no kind of incident" err.txt || fail "misspelt kind: $(cat err.txt)"

# Against the baseline: the new drive fault fails the run by default, in every format.
expect 1 "the new fault" "$NCSERVO" validate --baseline base.json --format json -o more.json \
  --report text:more.txt --report junit:more.xml --report sarif:more.sarif more.pcap
tail -1 more.txt | grep -q 'exit 1: findings at or above --fail-on error, 1 incident under --fail-on-incident any)$' ||
  fail "the reason: $(tail -1 more.txt)"
grep -q '^    incident 1 \[new\]: axis2 fault E09' more.txt &&
  grep -q '^    incident 2 \[unchanged\]: axis1 fault E09' more.txt || fail "text: $(grep incident more.txt)"
python3 - more.json more.xml more.sarif <<'PY' || fail "the new incident in JSON, JUnit and SARIF"
import json, sys, xml.etree.ElementTree as ET
report, junit, sarif = sys.argv[1:]
c = json.load(open(report))["captures"][0]
states = [(i["fingerprint"], i["baseline"]) for i in c["incidents"]]
assert states == [("drive-fault axis2 following-error #1", "new"),
                  ("drive-fault axis1 following-error #1", "unchanged")], states
assert c["baseline"]["incidents"] == {"new": 1, "unchanged": 1, "absent": 0}, c["baseline"]
assert c["baseline_absent_incidents"] == []
cases = [t for t in ET.parse(junit).getroot()[0].iter("testcase")
         if t.get("classname").endswith(".incidents")]
names = [(t.get("name"), t.find("failure") is not None) for t in cases]
assert names == [("INC-following-error drive-fault axis2 following-error #1", True),
                 ("INC-following-error drive-fault axis1 following-error #1", False)], names
failure = cases[0].find("failure")
assert failure.get("type") == "INC-following-error" and "axis2 fault E09" in failure.get("message")
run = json.load(open(sarif))["runs"][0]
rules = run["tool"]["driver"]["rules"]
results = [r for r in run["results"] if r["ruleId"].startswith("INC-")]
assert [(r["level"], r["baselineState"]) for r in results] == [("error", "new"),
                                                               ("warning", "unchanged")], results
for r in run["results"]:
    assert rules[r["ruleIndex"]]["id"] == r["ruleId"], r
    # GitHub code scanning rejects a result whose location has no region.startLine.
    assert r["locations"][0]["physicalLocation"]["region"]["startLine"] == 1, r
assert results[0]["properties"]["frame"] == c["incidents"][0]["frame"]
region = results[0]["relatedLocations"][0]["physicalLocation"]["region"]
assert region["byteOffset"] > 0 and region["byteLength"] > 16, region
PY
expect 1 "only the incident" "$NCSERVO" validate --baseline base.json --fail-on never \
  --fail-on-incident drive-fault more.pcap
tail -1 out.txt | grep -q '(exit 1: 1 incident under --fail-on-incident drive-fault)$' ||
  fail "the reason: $(tail -1 out.txt)"
expect 0 "--fail-on never alone" "$NCSERVO" validate --baseline base.json --fail-on never more.pcap
expect 0 "the baseline itself" "$NCSERVO" validate --baseline base.json base.pcap

# The other way round: the baseline's second fault is absent, and absence fails nothing.
"$NCSERVO" validate --format json -o more_base.json --fail-on never more.pcap
expect 0 "one incident fewer" "$NCSERVO" validate --baseline more_base.json --format json \
  -o fewer.json --report sarif:fewer.sarif base.pcap
python3 - fewer.json fewer.sarif <<'PY' || fail "the absent incident"
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]
absent = [i["fingerprint"] for i in c["baseline_absent_incidents"]]
assert absent == ["drive-fault axis2 following-error #1"], absent
results = json.load(open(sys.argv[2]))["runs"][0]["results"]
gone = [r for r in results if r.get("baselineState") == "absent" and r["ruleId"].startswith("INC-")]
assert len(gone) == 1 and gone[0]["kind"] == "pass" and gone[0]["level"] == "none", gone
assert gone[0]["locations"][0]["physicalLocation"]["region"] == {"startLine": 1}, gone
PY

# diff: the new incident exits 1 under the default and the kinds that name it.
expect 1 "diff" "$NCSERVO" diff base.pcap more.pcap
grep -q '^incidents\?:.*1 new' out.txt || grep -q 'incidents: 1 new' out.txt || fail "diff: $(head -3 out.txt)"
expect 1 "diff, the incident alone" "$NCSERVO" diff --fail-on never --fail-on-incident drive-fault \
  base.json more.pcap
expect 0 "diff, another kind" "$NCSERVO" diff --fail-on never --fail-on-incident esm base.pcap more.pcap
expect 0 "diff --fail-on never" "$NCSERVO" diff --fail-on never base.pcap more.pcap
expect 0 "diff, one fewer" "$NCSERVO" diff --fail-on never more.pcap base.pcap
echo "incident_gate: new incidents gate validate --baseline and diff; JUnit cases; SARIF INC- results"
