#!/usr/bin/env bash
# incident_truth.sh SRC BUILD
# Incidents against their makers' truth, on four captures: the simulator's incidents scenario
# (made here, also with --diagnosis: the drives' mailboxes and the ESC counters, and its link-fault
# incident), the independent generator's incident chains (made here) and the bundled
# captures/sim-incidents-4axis.pcap. First the truth itself, against what the tools show without
# the incident detector: each drive fault is a FAULT transition in tshark with the plugin, and
# nothing else is; the chain of each cause is in validate's findings and decode's values. Then
# `ncservo validate --format json` must list every incident of the truth (kind, axis, frame,
# cause) and nothing more, and tshark with the plugin must mark the same frames with
# ncservo.incident (docs/simulate.md#incidents, INTERFACES.md "Incidents").
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
CHECK_INCIDENTS="$SRC/tests/tools/check_incidents.py"

"$NCSERVO" simulate --scenario incidents -o "$WORK/sim.pcap" \
  --incidents-truth "$WORK/sim.incidents.json" 2>"$WORK/sim.err" ||
  fail "simulate --scenario incidents exit $?: $(cat "$WORK/sim.err")"
"$NCSERVO" simulate --scenario incidents --diagnosis --cycle-us 2000 --duration 8 -o "$WORK/simdiag.pcap" \
  --incidents-truth "$WORK/simdiag.incidents.json" 2>"$WORK/sim.err" ||
  fail "simulate --scenario incidents --diagnosis exit $?: $(cat "$WORK/sim.err")"
python3 "$GEN" --axes 4 --cycles 4000 --seed 5 --incident communication-loss \
  --incident overtemperature --incident following-error-after-step --incident link-fault \
  --incident bus-outage \
  --incidents "$WORK/gen.incidents.json" -o "$WORK/gen.pcap" || fail "gen_capture.py exit $?"
bundled="$SRC/captures/sim-incidents-4axis"
cp "$bundled.pcap" "$WORK/bundled.pcap"
cp "$bundled.incidents.json" "$WORK/bundled.incidents.json"

# docs/simulate.md's table of the scenario is the scenario: its rows in order give the truth's
# incidents (a bus outage row: the outage, then a drive fault on every axis).
python3 - "$SRC/docs/simulate.md" "$WORK/sim.incidents.json" "$WORK/simdiag.incidents.json" <<'PY' ||
import json, re, sys
text = open(sys.argv[1], encoding="utf-8").read()
section = text[text.index("## Incidents"):]
rows = re.findall(r"^\| `([a-z-]+)` \| ([^|]+) \| ([^|]+) \| ([^|]+) \|", section, re.M)
for path, diagnosis in ((sys.argv[2], False), (sys.argv[3], True)):
    want = []
    for cause, kind, axis, chain in rows:
        kind, axis = kind.strip(), axis.strip()
        if chain.strip().startswith("with `--diagnosis`") and not diagnosis:
            continue
        if kind.startswith("bus outage"):
            want.append(("bus-outage", None, cause))
            want += [("drive-fault", a, "communication-loss") for a in range(4)]
        else:
            want.append(({"drive fault": "drive-fault", "ESM fall": "esm"}[kind], int(axis), cause))
    truth = json.load(open(path))["incidents"]
    got = [(i["kind"], i["axis"], i["cause"]) for i in truth]
    if got != want:
        sys.exit(f"docs/simulate.md's incidents {want}\nthe scenario's {got} ({path})")
PY
  fail "docs/simulate.md's table of the incidents scenario differs from the scenario"

# --- the truth, against today's outputs ---
for name in sim simdiag gen bundled; do
  capture="$WORK/$name.pcap" truth="$WORK/$name.incidents.json"
  "$NCSERVO" validate --format json --fail-on never "$capture" >"$WORK/$name.json" ||
    fail "$name: validate exit $?"
  "$NCSERVO" decode --format csv "$capture" >"$WORK/$name.csv" || fail "$name: decode exit $?"
  "$TSHARK" "$PLUGIN" -2 -r "$capture" -T fields -E occurrence=a -E aggregator=, \
    -Y 'ncservo.transition == "FAULT REACTION ACTIVE" || ncservo.transition == "FAULT"' \
    -e frame.number -e ncservo.transition >"$WORK/$name.fault-frames" 2>"$WORK/tshark.err" ||
    fail "$name: tshark exit $?: $(cat "$WORK/tshark.err")"
  python3 - "$truth" "$WORK/$name.fault-frames" "$WORK/$name.json" "$WORK/$name.csv" "$name" <<'PY' ||
import csv, json, sys

truth = json.load(open(sys.argv[1]))["incidents"]
transitions = {}
for line in open(sys.argv[2]):
    frame, names = line.rstrip("\n").split("\t")
    transitions[int(frame)] = set(names.split(","))
findings = json.load(open(sys.argv[3]))["captures"][0]["findings"]
rows = list(csv.DictReader(open(sys.argv[4])))
name = sys.argv[5]
problems = []
time_of = {int(r["frame"]): float(r["time"]) for r in rows}

# A drive fault is the returned copy in which SEW.ServoErrors first reads 1: decode's state
# enters "fault reaction active" (the drive still enabled) or "error" (docs/protocol.md §6).
FAULTED = ("fault reaction active", "error")
entered, last = set(), {}
for r in rows:
    axis, state = int(r["axis"]), r["state"]
    if state in FAULTED and last.get(axis, "") not in FAULTED:
        entered.add((axis, int(r["frame"])))
    last[axis] = state
faults = {(i["axis"], i["frame"]) for i in truth if i["kind"] == "drive-fault"}
if faults != entered:
    problems.append(f"drive faults in decode's states not in the truth: {sorted(entered - faults)}; "
                    f"in the truth, not in decode: {sorted(faults - entered)}")
# The plugin shows the same: FAULT REACTION ACTIVE on each of these frames (FAULT when the drive
# was already off), and a FAULT otherwise only when the drive ends its reaction, within 100 ms.
fault_frames = {frame for _, frame in faults}
for frame, names in sorted(transitions.items()):
    if frame in fault_frames:
        continue
    if "FAULT REACTION ACTIVE" in names:
        problems.append(f"the plugin's FAULT REACTION ACTIVE on frame {frame} is not in the truth")
    elif not any(0 < time_of.get(frame, 0) - time_of.get(f, 1e18) <= 0.1 for f in fault_frames):
        problems.append(f"the plugin's FAULT on frame {frame} ends no drive fault of the truth")
for frame in sorted(fault_frames - set(transitions)):
    problems.append(f"the plugin shows no fault transition on frame {frame}")
WINDOW = 0.1  # the cause rows' 100 ms

def axis_rows(axis, t, before):
    """decode's rows of an axis from `before` seconds before t to t."""
    return [r for r in rows if int(r["axis"]) == axis and t - before <= float(r["time"]) <= t]

def rules_before(rule, t):
    return [f for f in findings if f["rule"] == rule and t - WINDOW <= f["time"] <= t]

for i in truth:
    frame, axis, cause = i["frame"], i["axis"], i["cause"]
    where = f"{i['kind']} at frame {frame}"
    if i["kind"] == "bus-outage":
        com5 = [f for f in findings if f["rule"] == "COM-005" and f["frame"] == frame]
        if len({f["axis"] for f in com5}) != 4:
            problems.append(f"{where}: COM-005 on {len(com5)} axes at that frame, not 4")
        continue
    if i["kind"] == "esm":
        if not [f for f in findings if f["rule"] == "ESM-003" and f["frame"] == frame]:
            problems.append(f"{where}: no ESM-003 on that AL status read")
        continue
    t = time_of.get(frame)
    if t is None:
        problems.append(f"{where}: decode has no row of that frame")
        continue
    if cause in ("communication-loss", "link-fault"):
        if not (rules_before("COM-001", t) or rules_before("COM-004", t)):
            problems.append(f"{where}: no COM-001 or COM-004 in the 100 ms before it")
    if cause == "link-fault":  # the counters' read after it names the link: LNK-001 within 10 s
        if not [f for f in findings if f["rule"] == "LNK-001" and t <= f["time"] <= t + 10]:
            problems.append(f"{where}: no LNK-001 in the 10 s after it")
    elif cause == "nc-command":
        if not [f for f in rules_before("SCW-001", t) if f["axis"] == axis]:
            problems.append(f"{where}: no SCW-001 on axis {axis} in the 100 ms before it")
    elif cause == "overtemperature":
        before = axis_rows(axis, t, 60)
        temps = [float(r["msg_data"]) for r in before if r["msg_code"] == "4"]
        warned = [r for r in before if r["ssw.temp_warning"] == "1"]
        if not temps or max(temps) < 90 or min(temps) > 50 or not warned:
            problems.append(f"{where}: no motor temperature climbing past 80 °C with "
                            "SSW.TempWarning before it")
    elif cause == "following-error-after-step":
        ssp = [int(r["ssp"]) for r in axis_rows(axis, t, WINDOW)]
        steps = [abs(b - a) for a, b in zip(ssp, ssp[1:])]
        if not steps or max(steps) < 100000:
            problems.append(f"{where}: no set-point step of 1000 rpm or more before it")
for p in problems:
    print(f"{name}: {p}", file=sys.stderr)
sys.exit(1 if problems else 0)
PY
    fail "$name: the truth does not match today's evidence"
done

# --- the incident detector against the truth ---
for name in sim simdiag gen bundled; do
  python3 "$CHECK_INCIDENTS" "$WORK/$name.incidents.json" --report "$WORK/$name.json" ||
    fail "$name: validate's incidents differ from the truth (exit $?; 2: no incident detector)"
  "$TSHARK" "$PLUGIN" -2 -r "$WORK/$name.pcap" -Y ncservo.incident -T fields -E occurrence=a \
    -E 'aggregator=|' -e frame.number -e ncservo.axis -e ncservo.incident \
    >"$WORK/$name.tshark" 2>"$WORK/tshark.err" || fail "$name: tshark exit $?: $(cat "$WORK/tshark.err")"
  [ ! -s "$WORK/tshark.err" ] || fail "$name: tshark: $(head -3 "$WORK/tshark.err")"
  python3 "$CHECK_INCIDENTS" "$WORK/$name.incidents.json" --tshark "$WORK/$name.tshark" ||
    fail "$name: the plugin's ncservo.incident differs from the truth"
done
echo "incident_truth: the simulator's (with and without --diagnosis), the generator's and the bundled incidents, in validate and tshark"
