#!/usr/bin/env bash
# layout_fit.sh SRC BUILD
# A configured layout that does not fit says so (docs/layout.md#a-layout-that-does-not-fit): the first
# axis's inputs two bytes early (on the outputs, as one LRW image allows) give exactly one warning, naming that axis, in the text, JSON, JSON
# Lines, SARIF and JUnit reports and on standard error; the exact configuration gives none.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
"$NCSERVO" simulate -o "$WORK/c.pcap" --layout-config "$WORK/exact.toml" 2>/dev/null
python3 - "$WORK/exact.toml" "$WORK/off.toml" <<'PY'
import sys, tomllib
axes = tomllib.load(open(sys.argv[1], "rb"))["axis"]
with open(sys.argv[2], "w") as out:
    for i, a in enumerate(axes):
        inputs = a["inputs"] + (-2 if i == 0 else 0)
        out.write(f'[[axis]]\nname = "{a["name"]}"\noutputs = {a["outputs"]:#x}\ninputs = {inputs:#x}\n')
PY

rc=0
"$NCSERVO" validate --config "$WORK/exact.toml" "$WORK/c.pcap" >"$WORK/out" 2>"$WORK/err" || rc=$?
[ "$rc" = 0 ] || fail "exact configuration: exit $rc"
! grep -q "does not fit" "$WORK/out" "$WORK/err" || fail "exact configuration: $(grep 'does not fit' "$WORK/out")"

"$NCSERVO" validate --config "$WORK/off.toml" "$WORK/c.pcap" >"$WORK/out" 2>"$WORK/err" || true
[ "$(grep -c '^warning: layout does not fit: ' "$WORK/out")" = 1 ] || fail "text: $(grep 'fit' "$WORK/out")"
grep -q "^warning: layout does not fit: axis0: the data at inputs 0x00010026 does not look like this protocol's TxPDO: .*message code [0-9]* outside 0..9" "$WORK/out" ||
  fail "text warning: $(grep 'does not fit' "$WORK/out")"
[ "$(grep -c 'layout does not fit: axis0' "$WORK/err")" = 1 ] || fail "stderr: $(cat "$WORK/err")"
# The warning comes before the findings it explains.
first=$(grep -n -m1 -v '^== ' "$WORK/out" | cut -d: -f1)
[ "$(sed -n "${first}p" "$WORK/out" | cut -c1-28)" = "warning: layout does not fit" ] || fail "not first: $(head -3 "$WORK/out")"
"$NCSERVO" validate --format json --config "$WORK/off.toml" "$WORK/c.pcap" >"$WORK/out" 2>/dev/null || true
python3 - "$WORK/out" <<'PY' || fail "json"
import json, sys
w = json.load(open(sys.argv[1]))["captures"][0]["layout"]["warnings"]
assert len(w) == 1 and w[0].startswith("axis0: the data at inputs 0x00010026"), w
PY
# The other formats carry it too: SARIF a notification, JUnit a test case, JSON Lines a line.
"$NCSERVO" validate --fail-on never --config "$WORK/off.toml" --format jsonl "$WORK/c.pcap" \
  --report sarif:"$WORK/off.sarif" --report junit:"$WORK/off.xml" >"$WORK/off.jsonl" 2>/dev/null ||
  fail "validate --report: exit $?"
python3 - "$WORK/off.sarif" "$WORK/off.xml" "$WORK/off.jsonl" <<'PY' || fail "sarif, junit, jsonl"
import json, sys, xml.etree.ElementTree as ET
want = "axis0: the data at inputs 0x00010026"
notes = json.load(open(sys.argv[1]))["runs"][0]["invocations"][0].get("toolExecutionNotifications", [])
fits = [n for n in notes if n["descriptor"]["id"] == "LAYOUT-FIT"]
assert len(fits) == 1 and fits[0]["level"] == "warning" and want in fits[0]["message"]["text"], notes
cases = [c for c in ET.parse(sys.argv[2]).iter("testcase") if c.get("name") == "layout fits the data"]
assert len(cases) == 1 and want in "".join(cases[0].itertext()), [ET.tostring(c) for c in cases]
lines = [json.loads(l) for l in open(sys.argv[3])]
warnings = [l["layout"]["warnings"] for l in lines if "layout" in l]
assert len(warnings) == 1 and len(warnings[0]) == 1 and warnings[0][0].startswith(want), warnings
PY
# The warning is no finding: under --fail-on warning it sets no exit status, and its JUnit case
# does not fail, so the two agree.
rc=0
"$NCSERVO" validate --fail-on warning --config "$WORK/off.toml" --format junit "$WORK/c.pcap" \
  >"$WORK/off-warning.xml" 2>/dev/null || rc=$?
python3 - "$WORK/off-warning.xml" <<'PY' || fail "junit under --fail-on warning"
import sys, xml.etree.ElementTree as ET
cases = [c for c in ET.parse(sys.argv[1]).iter("testcase") if c.get("name") == "layout fits the data"]
assert len(cases) == 1 and cases[0].find("failure") is None, [ET.tostring(c) for c in cases]
PY
[ $rc = "$(python3 -c 'import sys,xml.etree.ElementTree as E; print(1 if any(c.find("failure") is not None for c in E.parse(sys.argv[1]).iter("testcase")) else 0)' "$WORK/off-warning.xml")" ] ||
  fail "--fail-on warning: exit $rc disagrees with the JUnit report's failures"
# And nothing of it for the exact layout.
"$NCSERVO" validate --config "$WORK/exact.toml" --format jsonl "$WORK/c.pcap" \
  --report sarif:"$WORK/exact.sarif" --report junit:"$WORK/exact.xml" >"$WORK/exact.jsonl" 2>/dev/null
! grep -q 'LAYOUT-FIT\|layout fits the data\|"warnings"' "$WORK/exact.sarif" "$WORK/exact.xml" \
  "$WORK/exact.jsonl" || fail "exact configuration: a layout warning in SARIF, JUnit or JSON Lines"
echo "ok one warning for the axis off by two (text, JSON, JSON Lines, SARIF, JUnit), none for the exact layout"
