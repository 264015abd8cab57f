#!/usr/bin/env bash
# simulate_fault.sh SRC BUILD RULE [simulate options...]
# `ncservo simulate --fault RULE` followed by `ncservo validate` reports RULE, on the axis the
# fault was put on, plus only the companions captures/README.md documents for it (nothing else at
# all); and tshark with the plugin shows the finding on exactly the frames the validator reports.
SRC=$1 BUILD=$2 RULE=$3
shift 3
source "$SRC/tests/integration/lib.sh"
"$NCSERVO" simulate --fault "$RULE" "$@" -o "$WORK/capture.pcap" --layout-config "$WORK/layout.toml" \
  2>"$WORK/sim.err" || fail "simulate exit $?: $(cat "$WORK/sim.err")"
chmod a+r "$WORK/capture.pcap" "$WORK/layout.toml"
set +e
"$NCSERVO" validate --config "$WORK/layout.toml" --format json "$WORK/capture.pcap" \
  >"$WORK/report.json" 2>"$WORK/err.txt"
rc=$?
set -e
[ $rc = 0 ] || [ $rc = 1 ] || fail "validate exit $rc: $(cat "$WORK/err.txt")"
companions=$(grep "^| $RULE |" "$SRC/captures/README.md" | awk -F'|' '{ print $3 }' | xargs)
[ -n "$companions" ] || fail "captures/README.md documents no row for $RULE"
python3 - "$WORK/report.json" "$RULE" "$companions" <<'PY' || fail "$RULE: findings differ"
import json, sys
findings = json.load(open(sys.argv[1]))["captures"][0]["findings"]
rule, companions = sys.argv[2], sys.argv[3]
allowed = {rule} | (set() if companions == "-" else set(companions.split(",")))
fired = {f["rule"] for f in findings}
assert rule in fired, f"{rule} did not fire; fired {sorted(fired)}"
assert fired <= allowed, f"also fired {sorted(fired - allowed)} (allowed {sorted(allowed)})"
PY

slug=$("$NCSERVO" rules | awk -v id="$RULE" '$1 == id { print $2 }')
field="ncservo.rule.${slug//-/_}"
"$TSHARK" "$PLUGIN" -r "$WORK/capture.pcap" -o "ncservo.config:$WORK/layout.toml" -Y "$field" \
  -T fields -e frame.number >"$WORK/plugin.txt" 2>"$WORK/tshark.err" ||
  fail "tshark exit $?: $(cat "$WORK/tshark.err")"
[ ! -s "$WORK/tshark.err" ] || fail "tshark stderr: $(head -3 "$WORK/tshark.err")"
python3 - "$WORK/report.json" "$WORK/plugin.txt" "$RULE" <<'PY' || fail "$RULE: plugin and validator disagree"
import json, sys
findings = json.load(open(sys.argv[1]))["captures"][0]["findings"]
want = sorted({f["frame"] for f in findings if f["rule"] == sys.argv[3]})
shown = sorted({int(l) for l in open(sys.argv[2]) if l.strip()})
assert want == shown, f"validator frames {want}, plugin frames {shown}"
PY
echo "simulate_fault: $RULE fires (companions: $companions), and the plugin shows it on the same frames"
