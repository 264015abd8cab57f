#!/usr/bin/env bash
# task_timing.sh SRC BUILD
# Two tasks (docs/timing.md#which-frames): 1 ms servo frames beside a 10 ms I/O frame. Each cyclic
# frame keeps its own clock and is listed with its cycle; the capture's cycle and latency
# statistics are the servos' task's, so the slower frame's 10 ms intervals appear in neither the
# summary line nor the timing statistics. A capture with no servo keeps every frame in them.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

"$NCSERVO" simulate --no-startup --io-slaves 4 --io-task-us 10000 --duration 3 -o "$WORK/t.pcap" \
  2>/dev/null || fail "simulate"
"$NCSERVO" validate --fail-on never "$WORK/t.pcap" >"$WORK/t.txt" || fail "validate exit $?"
grep -q '^.*t.pcap: [0-9]* frames, 3000 cycles, cycle 1000.0 us (p99 1000.0, max 1000.0)$' "$WORK/t.txt" ||
  fail "summary line: $(head -1 "$WORK/t.txt")"
grep -q '^cyclic frames: LRW 0x00010000 every 1000.0 us, 3000 cycles; LRW 0x00011000 every 10000.0 us, 300 cycles$' \
  "$WORK/t.txt" || fail "cyclic frames: $(grep '^cyclic frames' "$WORK/t.txt")"
"$NCSERVO" validate --format json --fail-on never "$WORK/t.pcap" >"$WORK/t.json" || fail "validate json"
python3 - "$WORK/t.json" <<'PY' || fail "JSON timing"
import json, sys
timing = json.load(open(sys.argv[1]))["captures"][0]["timing"]
cycle = timing["cycle_us"]
assert cycle["count"] == 2999 and cycle["max"] == 1000.0 and cycle["p99"] == 1000.0, cycle
assert [f["cycle_us"] for f in timing["cyclic_frames"]] == [1000.0, 10000.0], timing["cyclic_frames"]
assert timing["latency_us"]["count"] == 3000, timing["latency_us"]
PY
# With no servo (no layout) every cyclic frame feeds the statistics, as on an I/O rig's capture.
"$NCSERVO" validate --format json --fail-on never --no-default-layout "$WORK/t.pcap" \
  >"$WORK/none.json" 2>/dev/null || true
python3 - "$WORK/none.json" <<'PY' || fail "no servo: JSON timing"
import json, sys
capture = json.load(open(sys.argv[1]))["captures"][0]
assert capture["verdict"] == "no servo", capture["verdict"]
cycle = capture["timing"]["cycle_us"]
assert cycle["count"] == 2999 + 299 and cycle["max"] == 10000.0, cycle
PY
echo "task_timing: the capture's cycle statistics are the servo task's; each frame its own cycle"
