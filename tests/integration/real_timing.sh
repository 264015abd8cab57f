#!/usr/bin/env bash
# real_timing.sh SRC BUILD
# Bus health on real captures without servos (docs/timing.md "Which frames"): the cyclic frames
# are worked out here from stock tshark's fields, and `ncservo validate --format json` must agree.
# A cyclic frame is a frame whose logical datagrams (command, address, length) repeat; its master
# copies are the copies with every WKC 0. Checked per capture:
# - timing.cyclic_datagrams: the datagrams of the cyclic frames with two master copies or more,
#   each with the frames (both copies) of the cyclic frames holding it;
# - cycles: the master copies of the busiest cyclic frame;
# - timing.cycle_us: its count and its median are those of frame.time_delta_displayed when tshark
#   shows only one cyclic frame's master copies, over every cyclic frame, within each segment (a
#   jump back by more than 1 ms or forward by more than 1 s starts one, docs/timing.md#rule-time);
# - timing.latency_us: one return latency per master copy whose returned copy came;
# - findings: no COM-001 or COM-004 (these captures return every frame with steady WKCs), and
#   COM-002 on exactly the master copies that come more than 1.5 x the running median interval
#   (at 1 us) after the previous one, once 8 intervals were seen in the segment (COM-002),
#   each reported at the next master copy, late or lost as the interval after it says.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_path "$REAL_CAPTURES" "real captures"
real=$REAL_CAPTURES
judged=0
for capture in "$real"/*.pcap "$real"/*.pcapng "$real"/*.cap; do
  [ -f "$capture" ] || continue
  name=$(basename "$capture")
  rc=0
  "$NCSERVO" validate --format json --fail-on never "$capture" >"$WORK/report.json" || rc=$?
  [ $rc = 4 ] || fail "$name: validate exit $rc, expected 4 (no servo)"
  tshark -r "$capture" -T fields -E separator=/t -E occurrence=a -E aggregator=, -e frame.number \
    -e frame.time_epoch -e ecat.cmd -e ecat.lad -e ecat.subframe.length -e ecat.cnt \
    >"$WORK/frames.tsv" 2>/dev/null || fail "$name: tshark exit $?"
  # The cyclic frames' master copies, one frame number list per cyclic frame.
  python3 - "$WORK/frames.tsv" "$WORK/groups" <<'PY' || fail "$name: grouping"
import json, sys
frames = []
for line in open(sys.argv[1]):
    number, epoch, cmds, lads, lengths, wkcs = (line.rstrip("\n").split("\t") + [""] * 6)[:6]
    if not cmds:
        continue
    cmds = [int(c, 16) for c in cmds.split(",")]
    lads = iter(lads.split(",")) if lads else iter(())
    lengths = [int(n) for n in lengths.split(",")]
    logical = tuple((c, int(next(lads), 16), n) for c, n in zip(cmds, lengths) if c in (10, 11, 12))
    if logical:
        master = all(int(w) == 0 for w in wkcs.split(","))
        frames.append({"frame": int(number), "logical": logical, "master": master})
groups = {}
for f in frames:
    groups.setdefault(f["logical"], []).append(f)
cyclic = [{"datagrams": list(k), "frames": len(v), "masters": [f["frame"] for f in v if f["master"]],
           "returned": [f["frame"] for f in v if not f["master"]]}
          for k, v in groups.items() if sum(f["master"] for f in v) >= 2]
json.dump(cyclic, open(sys.argv[2] + ".json", "w"))
for i, g in enumerate(cyclic):
    open(f"{sys.argv[2]}.{i}", "w").write(",".join(map(str, g["masters"])))
PY
  # tshark's own intervals between the master copies of each cyclic frame.
  : >"$WORK/deltas.tsv"
  for list in "$WORK"/groups.[0-9]*; do
    [ -f "$list" ] || continue
    tshark -r "$capture" -Y "frame.number in {$(cat "$list")}" -T fields -e frame.number \
      -e frame.time_delta_displayed >>"$WORK/deltas.tsv" 2>/dev/null || fail "$name: tshark exit $?"
    judged=$((judged + 1))
  done
  python3 - "$WORK/report.json" "$WORK/groups.json" "$WORK/deltas.tsv" "$WORK/frames.tsv" <<'PY' || fail "$name: ncservo and tshark disagree"
import json, sys
from decimal import Decimal
capture = json.load(open(sys.argv[1]))["captures"][0]
groups = json.load(open(sys.argv[2]))
timing = capture["timing"]
names = {10: "LRD", 11: "LWR", 12: "LRW"}

# Segments: a jump back by more than 1 ms or forward by more than 1 s starts one.
segment, previous, segment_of, time_of = 0, None, {}, {}
for line in open(sys.argv[4]):
    number, epoch = line.split("\t")[:2]
    t = Decimal(epoch)
    if previous is not None and (t < previous - Decimal("0.001") or t > previous + 1):
        segment += 1
    previous = t
    segment_of[int(number)], time_of[int(number)] = segment, t

# tshark's frame.time_delta_displayed between consecutive master copies of one cyclic frame,
# where both lie in one segment and time did not go back.
intervals = {}  # frame -> (ns, previous master copy)
rows = [l.split("\t") for l in open(sys.argv[3]) if l.strip()]
by_group, start = [], 0
for g in groups:
    by_group.append(rows[start:start + len(g["masters"])])
    start += len(g["masters"])
for g, shown in zip(groups, by_group):
    assert [int(r[0]) for r in shown] == g["masters"], "tshark showed other frames"
    for (a, _), (b, delta) in zip(shown, shown[1:]):
        ns = int(Decimal(delta.strip()) * 1_000_000_000)
        if segment_of[int(a)] == segment_of[int(b)] and ns >= 0:
            intervals[int(b)] = (ns, int(a))

expected_datagrams = []
for g in groups:
    for cmd, address, length in g["datagrams"]:
        entry = {"command": names[cmd], "address": f"0x{address:08X}", "length": length, "frames": 0}
        same = [d for d in expected_datagrams if {**d, "frames": 0} == entry]
        (same[0] if same else expected_datagrams.append(entry) or entry)["frames"] += g["frames"]
assert timing["cyclic_datagrams"] == expected_datagrams, (timing["cyclic_datagrams"], expected_datagrams)
assert capture["cycles"] == max([len(g["masters"]) for g in groups], default=0), capture["cycles"]

values = sorted(ns for ns, _ in intervals.values())
if not values:
    assert timing["cycle_us"] is None, timing["cycle_us"]
else:
    cycle = timing["cycle_us"]
    assert cycle is not None, "no cycle statistics"
    assert cycle["count"] == len(values), (cycle["count"], len(values))
    median = values[(len(values) - 1) // 2]  # the lower median (docs/timing.md)
    assert round(cycle["median"] * 1000) == median, (cycle["median"], median)

# One return latency per master copy whose returned copy came before the next master copy.
latencies = 0
for g in groups:
    copies = sorted([(f, True) for f in g["masters"]] + [(f, False) for f in g["returned"]])
    pending = None
    for frame, master in copies:
        if pending is not None and segment_of[frame] != segment_of[pending]:
            pending = None
        if master:
            pending = frame
        elif pending is not None and time_of[frame] >= time_of[pending]:
            latencies += 1
            pending = None
latency = timing["latency_us"]
assert (latency["count"] if latency else 0) == latencies, (latency, latencies)

# COM-002 where the running median (1 us buckets, rounded) of the segment's intervals says so,
# judged at the cyclic frame's next master copy: late when the gap and the interval after it
# round to two cycles, else lost (the capture's last frame when no next copy came).
gaps, seen, current = [], [], None
next_of = {since: (frame, ns) for frame, (ns, since) in intervals.items()}
last_frame = max(time_of)
for frame in sorted(intervals):
    ns, since = intervals[frame]
    if segment_of[frame] != current:
        seen, current = [], segment_of[frame]
    if len(seen) >= 8:
        median = sorted(seen)[(len(seen) - 1) // 2] * 1000
        if ns * 2 > median * 3:
            if frame in next_of and segment_of[next_of[frame][0]] == segment_of[frame]:
                told, after = next_of[frame]
                late = round((ns + after) / median) == 2
            else:
                told, late = last_frame, False
            gaps.append((told, "late" if late else "lost"))
    seen.append((ns + 500) // 1000)
rules = [f["rule"] for f in capture["findings"]]
assert "COM-001" not in rules and "COM-004" not in rules, capture["findings"]
reported = sorted((f["frame"], "late" if f["message"].startswith("late") else "lost")
                  for f in capture["findings"] if f["rule"] == "COM-002")
assert reported == sorted(gaps), (reported, gaps)
print(f"  {len(groups)} cyclic frames, {len(values)} intervals, {latencies} latencies, {len(gaps)} gaps")
PY
  echo "ok $name"
done
[ $judged -ge 3 ] || fail "only $judged cyclic frames in the real captures"
# One source, one rounding: the summary's cycle time is the timing series' (docs/cli.md), on a
# capture whose PC stamps make the two methods differ in the last digits (5142.59 vs 5143.0).
"$NCSERVO" validate --format json --fail-on never --allow-empty "$real/ethercrab-dc-to-op.pcapng" \
  >"$WORK/one.json" ||
  fail "ethercrab-dc-to-op: validate exit $?"
python3 - "$WORK/one.json" <<'PY' || fail "cycle_time_us and timing.cycle_us disagree"
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]
summary, series = c["cycle_time_us"], c["timing"]["cycle_us"]
assert summary == {k: series[k] for k in ("median", "p99", "max")}, (summary, series)
PY
