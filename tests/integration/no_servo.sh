#!/usr/bin/env bash
# no_servo.sh SRC BUILD
# Nothing checked is not a pass (docs/cli.md, exit status 4): a capture with no servo of this
# protocol, or a configured axis that never appears, ends "NO SERVO" with exit 4 in every format,
# 0 with --allow-empty; with several captures the most serious status wins, in the order
# 2, 3, 1, 4, 0.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_path "$REAL_CAPTURES" "real captures"
empty="$REAL_CAPTURES/wiki-beckhoff-startup.cap"              # no servo, no finding
empty_findings="$REAL_CAPTURES/soem-akd-servo-pdo-mapping.pcapng"  # no servo, a bus finding
clean="$SRC/captures/commissioning-4axis.pcap"
faults="$SRC/captures/faults-4axis.pcap"
[ -f "$empty" ] && [ -f "$empty_findings" ] || fail "the real captures at $REAL_CAPTURES lack $empty or $empty_findings"

# status EXPECTED ARGS...: runs validate, checks its exit status
status() {
  local expected=$1 rc=0
  shift
  "$NCSERVO" validate "$@" >"$WORK/out" 2>"$WORK/err" || rc=$?
  [ "$rc" = "$expected" ] || fail "validate $*: exit $rc, expected $expected: $(head -3 "$WORK/err")"
}

# Each format says it.
status 4 "$empty"
grep -q "^NO SERVO: no servo of this protocol found" "$WORK/out" || fail "text: no NO SERVO line"
grep -q "^verdict: NO SERVO - 0 errors, .*1 with no servo checked" "$WORK/out" || fail "text verdict: $(tail -1 "$WORK/out")"
status 4 --format json "$empty"
python3 -c 'import json,sys; c=json.load(open(sys.argv[1]))["captures"][0]; assert c["verdict"] == "no servo" and "no servo" in c["reason"], c' \
  "$WORK/out" || fail "json"
status 4 --format jsonl "$empty"
python3 -c 'import json,sys; l=[json.loads(x) for x in open(sys.argv[1])]; assert l[-1]["verdict"] == "no servo" and l[-1]["reason"], l' \
  "$WORK/out" || fail "jsonl"
status 4 --format junit "$empty"
python3 - "$WORK/out" <<'PY' || fail "junit"
import sys, xml.etree.ElementTree as ET
suite = ET.parse(sys.argv[1]).getroot().find("testsuite")
skipped = suite.findall("testcase/skipped")
assert int(suite.get("skipped")) == len(skipped) > 0, suite.attrib
# every rule that did not fire is skipped; a rule off by default says so
assert all(len(case) == 1 for case in suite.findall("testcase")), suite.attrib
assert all(s.text.startswith(("NO SERVO: no servo of this protocol", "off by default")) for s in skipped)
PY
status 4 --format sarif "$empty"
python3 - "$WORK/out" <<'PY' || fail "sarif"
import json, sys
run = json.load(open(sys.argv[1]))["runs"][0]
n = run["invocations"][0]["toolExecutionNotifications"]
assert len(n) == 1 and n[0]["level"] == "error" and "NO SERVO" in n[0]["message"]["text"], n
PY
echo "ok every format"

# --allow-empty: 0, and the report still says why.
status 0 --allow-empty "$empty"
# The words still say what the capture is: nothing checked is no pass (docs/cli.md#verdicts).
grep -q "^verdict: NO SERVO .*1 with no servo checked (exit 0: .*--allow-empty)$" "$WORK/out" ||
  fail "allow-empty text: $(tail -1 "$WORK/out")"
! grep -q PASS "$WORK/out" || fail "allow-empty: PASS in the text"
grep -q "^NO SERVO: " "$WORK/out" || fail "allow-empty: reason gone"
status 0 --allow-empty --format json "$empty"
python3 -c 'import json,sys; c=json.load(open(sys.argv[1]))["captures"][0]; assert c["verdict"] == "no servo" and c["reason"], c' \
  "$WORK/out" || fail "allow-empty json"
status 0 --allow-empty --format sarif "$empty"
grep -q '"level": "note"' "$WORK/out" || fail "allow-empty sarif: not a note"
# --fail-on never does not hide it
status 4 --fail-on never "$empty"
echo "ok --allow-empty"

# A configured axis that never appears is named and counts the same way.
"$NCSERVO" simulate --scenario commissioning --axes 2 --seed 3 -o "$WORK/two.pcap" \
  --layout-config "$WORK/two.toml" 2>/dev/null
status 0 --config "$WORK/two.toml" "$WORK/two.pcap"
cat "$WORK/two.toml" >"$WORK/three.toml"
printf '\n[[axis]]\nname = "ghost"\noutputs = 0x00070000\ninputs = 0x00070100\n' >>"$WORK/three.toml"
status 4 --config "$WORK/three.toml" "$WORK/two.pcap"
grep -q "^NO SERVO: configured axis never in the capture: ghost" "$WORK/out" || fail "ghost not named: $(cat "$WORK/out")"
status 4 --config "$WORK/three.toml" --format json "$WORK/two.pcap"
python3 -c 'import json,sys; c=json.load(open(sys.argv[1]))["captures"][0]; assert c["missing_axes"] == ["ghost"] and c["verdict"] == "no servo", c' \
  "$WORK/out" || fail "missing_axes"
status 0 --allow-empty --config "$WORK/three.toml" "$WORK/two.pcap"
echo "ok configured axis missing"

# Precedence over several captures: 2, 3, 1, 4, 0.
status 4 "$clean" "$empty"
status 4 "$empty" "$clean"
status 1 "$empty" "$faults"
status 1 "$faults" "$empty"
status 1 "$empty_findings"
status 3 "$empty" "$WORK/missing.pcap"
status 3 "$WORK/missing.pcap" "$faults" "$empty"
status 2 --timestamps bogus "$empty"
status 0 --allow-empty "$empty" "$clean"
status 1 --allow-empty "$empty" "$faults"
echo "ok precedence"
