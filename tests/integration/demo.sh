#!/usr/bin/env bash
# demo.sh SRC BUILD: `.ci/demo` (README's first two commands) shows what the README says it shows:
# every axis of captures/commissioning-4axis.pcap at the first enable (frames 80-96, inside the
# plugin's learning window, so tshark must run in two passes), while moving (1700-1710) and at the
# emergency stop (3450-3460); then validate passes the clean capture and fails the faults one.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
NCSERVO_BUILD=$BUILD "$SRC/.ci/demo" >"$WORK/out" 2>"$WORK/err" || fail ".ci/demo exited $?: $(tail -5 "$WORK/err")"
python3 - "$WORK/out" <<'PY' || fail "the demo's tshark table: $(head -5 "$WORK/out")"
import sys
rows = {}
for line in open(sys.argv[1]):
    cells = line.rstrip("\n").split("\t")
    if len(cells) == 6 and cells[0].isdigit():
        rows[int(cells[0])] = cells
for first, last in ((80, 96), (1700, 1710), (3450, 3460)):
    shown = [n for n in range(first, last + 1) if n in rows]
    assert shown, f"no frame of {first}-{last}"
    assert all(rows[n][1] == "axis0,axis1,axis2,axis3" for n in shown), [rows[n][1] for n in shown]
# The first enable: axis0 goes from ready to switch on to control active in 80-96.
states = [rows[n][4].split(",")[0] for n in range(80, 97) if n in rows]
assert states[0] == "ready to switch on" and states[-1] == "control active", states
PY
grep -q '^verdict: PASS .* in 1 capture (exit 0: 1 incident not gated (--fail-on-incident never))$' "$WORK/out" || fail "no PASS for the clean capture"
grep -q '^verdict: FAIL .*(exit 0: --fail-on never)$' "$WORK/out" || fail "no FAIL for the faults capture"
echo "demo: the first enable, the motion and the emergency stop of every axis, then the verdicts"
