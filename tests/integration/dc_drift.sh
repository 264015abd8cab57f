#!/usr/bin/env bash
# dc_drift.sh SRC BUILD: the reference clock's drift (docs/timing.md#drift) against the truth the
# simulator was given (`simulate --dc-drift PPM`): within the uncertainty validate gives it, and the
# text says which clock it is measured against. A PC whose stamps come late by a random amount
# (`--capture-stamps late:`) widens the uncertainty
# instead of moving the drift outside it; the drift does not change what the rules find.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

check() {  # check NAME PPM SIMULATE-OPTIONS...
  local name=$1 ppm=$2
  shift 2
  "$NCSERVO" simulate --scenario commissioning --duration 3 --seed 5 --dc-drift "$ppm" "$@" \
    -o "$WORK/$name.pcap" 2>/dev/null || fail "$name: simulate exited $?"
  "$NCSERVO" validate --fail-on never --format json "$WORK/$name.pcap" >"$WORK/$name.json"
  "$NCSERVO" validate --fail-on never "$WORK/$name.pcap" >"$WORK/$name.txt"
  grep -q "^distributed clocks (drift against the capture's own timestamps, ± at 95 %):" \
    "$WORK/$name.txt" || fail "$name: no drift line naming its clock: $(grep -A2 distributed "$WORK/$name.txt")"
  python3 - "$WORK/$name.json" "$ppm" "$name" <<'PY' || fail "$name"
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]
truth, name = float(sys.argv[2]), sys.argv[3]
reference = [s for s in c["timing"]["dc"] if s["reference"]]
assert reference, f"{name}: no reference clock in {c['timing']['dc']}"
r = reference[0]
drift, plus_minus = r["drift_ppm"], r["drift_uncertainty_ppm"]
assert drift is not None and plus_minus is not None, r
# The report rounds both to the thousandth of a ppm.
assert abs(drift - truth) <= plus_minus + 0.002, f"{name}: {drift} ± {plus_minus} ppm, truth {truth}"
print(f"{name}: {drift:+.3f} ± {plus_minus:.3f} ppm (truth {truth:+})")
with open(sys.argv[1] + ".uncertainty", "w") as out:
    out.write(str(plus_minus))
PY
}

check still 0
check fast 80
check slow -25.5
check jittered 80 --capture-stamps late:100us
python3 - "$WORK/fast.json.uncertainty" "$WORK/jittered.json.uncertainty" <<'PY' || fail "the jitter did not widen the uncertainty"
import sys
clean, jittered = (float(open(p).read()) for p in sys.argv[1:3])
assert jittered > 3 * clean, (clean, jittered)
PY
python3 - "$WORK/still.json" "$WORK/fast.json" <<'PY' || fail "a drifting reference clock changed the findings"
import json, sys
seen = lambda p: [(f["rule"], f["frame"]) for f in json.load(open(p))["captures"][0]["findings"]]
assert seen(sys.argv[1]) == seen(sys.argv[2]), (seen(sys.argv[1])[:5], seen(sys.argv[2])[:5])
PY
rc=0
"$NCSERVO" simulate --dc-drift 5000 -o "$WORK/bad.pcap" 2>"$WORK/bad.err" || rc=$?
[ "$rc" = 2 ] || fail "--dc-drift 5000: exit $rc, expected 2"
grep -q -- '--dc-drift 5000' "$WORK/bad.err" || fail "--dc-drift 5000: $(cat "$WORK/bad.err")"
echo "dc_drift: the reference clock's drift within its uncertainty of the truth, on the named clock"
