#!/usr/bin/env bash
# last_cycle_gap.sh SRC BUILD: a capture whose last cycle comes after a gap. Only the end of the
# capture can judge that gap (docs/rules.md#com-002: "the capture ends before the next cycle"),
# and every command that shows findings shows it on the last frame: validate, and decode
# --format vcd on the bus's findings signal at the last frame's time. decode's csv and jsonl rows
# carry no findings: their rows are the same with the gap judged or not.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

"$NCSERVO" simulate --scenario commissioning --axes 2 --seed 3 -o "$WORK/sim.pcap" 2>/dev/null
frames=$(tshark -r "$WORK/sim.pcap" -T fields -e frame.number 2>/dev/null | tail -1)
# Five cycles (a master and a returned copy each) cut before the last one.
editcap "$WORK/sim.pcap" "$WORK/gap.pcap" "$((frames - 11))-$((frames - 2))"
last=$((frames - 10))

"$NCSERVO" validate --format jsonl --fail-on never "$WORK/gap.pcap" >"$WORK/findings.jsonl"
python3 - "$WORK/findings.jsonl" "$last" <<'PY' || fail "validate: no COM-002 on the last frame"
import json, sys
last = int(sys.argv[2])
gaps = [d for d in map(json.loads, open(sys.argv[1])) if d.get("rule") == "COM-002"]
ends = [d for d in gaps if d["frame"] == last and "the capture ends before the next cycle" in d["message"]]
if len(ends) != 1:
    print("COM-002 findings:", gaps, file=sys.stderr)
    sys.exit(1)
PY

"$NCSERVO" decode --format vcd -o "$WORK/gap.vcd" "$WORK/gap.pcap" 2>"$WORK/decode.err" ||
  fail "decode --format vcd exited $?: $(cat "$WORK/decode.err")"
last_time=$(tshark -r "$WORK/gap.pcap" -T fields -e frame.time_relative 2>/dev/null | tail -1)
python3 - "$WORK/gap.vcd" "$last_time" <<'PY' || fail "decode --format vcd: COM-002 not shown at the last frame"
import sys
vcd, last_ns = open(sys.argv[1]).read().split("\n"), round(float(sys.argv[2]) * 1e9)
bus_findings, scope, time, shown = None, None, None, []
for line in vcd:
    parts = line.split()
    if parts[:2] == ["$scope", "module"]:
        scope = parts[2]
    elif parts[:1] == ["$var"] and scope == "bus" and parts[4] == "findings":
        bus_findings = parts[3]
    elif line.startswith("#"):
        time = int(line[1:])
    elif line.startswith("s") and len(parts) == 2 and parts[1] == bus_findings:
        shown.append((time, parts[0][1:].split(",")))
at_end = [rules for t, rules in shown if t == last_ns]
if bus_findings is None or not any("COM-002" in rules for rules in at_end):
    print(f"bus findings ({bus_findings}) shown: {shown[-5:]}; last frame at {last_ns} ns", file=sys.stderr)
    sys.exit(1)
PY
echo "last-cycle gap: COM-002 on frame $last in validate and in decode's VCD"
