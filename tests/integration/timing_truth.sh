#!/usr/bin/env bash
# timing_truth.sh SRC BUILD
# The timing statistics (docs/timing.md) against what the simulator injected: with late and lost
# cycles and a fixed return latency the truth is known exactly; with send jitter it is the sorted
# intervals of the capture's own timestamps (stock tshark); the same numbers come out of an ESL
# probe's capture of the same run, whose capture timestamps are noisy. COM-002 says "late" and
# "lost" for what was injected as such.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

timing() {  # timing CAPTURE: the JSON report's timing object
  "$NCSERVO" validate --format json --fail-on never "$1" |
    python3 -c 'import json, sys; json.dump(json.load(sys.stdin)["captures"][0]["timing"], sys.stdout)'
}

# Exact truth: 1 ms cycles, the one at 0.5 s sent 300 us late, 3 cycles lost from 1.2 s, returned
# copies 120 us after their master copy.
"$NCSERVO" simulate --no-startup --axes 2 --duration 2 --latency-us 120 --late-cycle 0.5:300 \
  --lost-cycles 1.2:3 -o "$WORK/late.pcap" 2>/dev/null
timing "$WORK/late.pcap" >"$WORK/late.json"
python3 - "$WORK/late.json" <<'PY' || fail "late and lost cycles: $(head -c 600 "$WORK/late.json")"
import json, sys
t = json.load(open(sys.argv[1]))
c, l = t["cycle_us"], t["latency_us"]
# 2000 slots, 3 not sent: 1997 master copies, 1996 intervals; the late one is 1300 then 700 us.
assert c["count"] == 1996, c["count"]
assert (c["min"], c["median"], c["max"]) == (700.0, 1000.0, 4000.0), c
assert c["p1"] == 1000.0 and c["p99"] == 1000.0, c
assert [w["interval_us"] for w in t["worst_cycles"][:2]] == [4000.0, 1300.0], t["worst_cycles"]
assert all(w["interval_us"] == 1000.0 for w in t["worst_cycles"][2:]), t["worst_cycles"]
assert (l["count"], l["min"], l["median"], l["max"], l["stddev"]) == (1997, 120.0, 120.0, 120.0, 0.0), l
assert all(w["frame"] == w["master_frame"] + 1 for w in t["worst_latencies"]), t["worst_latencies"]
bins = {(b["from_us"], b["to_us"]): b["count"] for b in c["histogram"]}
assert bins == {(-300.0, -290.0): 1, (0.0, 1.0): 1993, (300.0, 310.0): 1, (3000.0, 3100.0): 1}, bins
assert c["over"] == 0 and c["under"] == 0, c  # 3000 us over nominal is still in range
PY

# Send jitter of ±25 us: the truth is the capture's own master-copy intervals, sorted.
opts=(simulate --no-startup --axes 4 --duration 3 --jitter-us 25 --latency-us 40 --seed 9)
"$NCSERVO" "${opts[@]}" -o "$WORK/jitter.pcap" 2>/dev/null
"$NCSERVO" "${opts[@]}" --probe esl -o "$WORK/jitter-esl.pcap" 2>/dev/null
tshark -r "$WORK/jitter.pcap" -T fields -e frame.time_epoch -e eth.src >"$WORK/times.tsv" 2>/dev/null
timing "$WORK/jitter.pcap" >"$WORK/jitter.json"
timing "$WORK/jitter-esl.pcap" >"$WORK/jitter-esl.json"
python3 - "$WORK/times.tsv" "$WORK/jitter.json" "$WORK/jitter-esl.json" <<'PY' || fail "jitter: $(head -c 600 "$WORK/jitter.json")"
import json, math, sys
from decimal import Decimal
masters, latencies, last = [], [], None
for line in open(sys.argv[1]):
    epoch, src = line.split()
    ns = int(Decimal(epoch) * 10**9)
    if int(src.split(":")[0], 16) & 0x02:  # the returned copy (locally administered source)
        latencies.append(ns - last)
    else:
        masters.append(ns)
        last = ns
intervals = sorted(b - a for a, b in zip(masters, masters[1:]))
def rank(values, q):
    return values[max(math.ceil(q * len(values)), 1) - 1] / 1000
mean = sum(intervals) / len(intervals)
sd = math.sqrt(sum((v - mean) ** 2 for v in intervals) / len(intervals)) / 1000
# The injected jitter itself: the difference of two uniform integers in [-25, 25] us.
sd_injected = math.sqrt(2 * ((51 ** 2 - 1) / 12))
for path, timestamps in ((sys.argv[2], "capture"), (sys.argv[3], "probe")):
    t = json.load(open(path))
    c = t["cycle_us"]
    assert t["timestamps"] == timestamps, (path, t["timestamps"])
    assert c["count"] == len(intervals), (path, c["count"], len(intervals))
    assert (c["min"], c["median"], c["max"]) == (intervals[0] / 1000, rank(intervals, 0.5), intervals[-1] / 1000), (path, c)
    assert abs(c["p99"] - rank(intervals, 0.99)) <= 0.01 * rank(intervals, 0.99), (path, c)
    assert abs(c["stddev"] - sd) <= 0.02 * sd, (path, c["stddev"], sd)
    assert abs(c["stddev"] - sd_injected) <= 0.05 * sd_injected, (path, c["stddev"], sd_injected)
    assert t["worst_cycles"][0]["interval_us"] == intervals[-1] / 1000, (path, t["worst_cycles"])
    l = t["latency_us"]
    assert (l["min"], l["median"], l["max"]) == (40.0, 40.0, 40.0), (path, l)
    assert sum(b["count"] for b in c["histogram"]) + c["under"] + c["over"] == c["count"], path
PY
# COM-002 tells late from lost: a cycle sent 700 us late (1.7 ms, then 0.3 ms) is late with
# nothing missing, 3 cycles not sent are lost; the same through an ESL probe's timestamps.
gap_opts=(simulate --no-startup --axes 2 --duration 2 --late-cycle 0.5:700 --lost-cycles 1.2:3)
"$NCSERVO" "${gap_opts[@]}" -o "$WORK/gaps.pcap" 2>/dev/null
"$NCSERVO" "${gap_opts[@]}" --probe esl -o "$WORK/gaps-esl.pcap" 2>/dev/null
for capture in gaps gaps-esl; do
  "$NCSERVO" validate --format json --fail-on never "$WORK/$capture.pcap" >"$WORK/$capture.json"
  python3 - "$WORK/$capture.json" <<'PY' || fail "$capture: COM-002 late and lost: $(grep -o '"COM-002"[^}]*' "$WORK/$capture.json")"
import json, sys
findings = [f for f in json.load(open(sys.argv[1]))["captures"][0]["findings"] if f["rule"] == "COM-002"]
assert len(findings) == 2, findings
late, lost = (f["message"] for f in findings)
assert late.startswith("late cycle: 1.700 ms from frame ") and "then 0.300 ms; nothing missing" in late, late
assert lost.startswith("3 cycles lost: 4.000 ms from frame ") and "then 1.000 ms" in lost, lost
PY
done

# COM-006 and COM-007 enabled with their default limits stay quiet on a clean jittered run
# (±25 us of a 1 ms cycle, 40 us latency); with limits the run exceeds they fire, once each.
for capture in jitter jitter-esl; do
  "$NCSERVO" validate --enable COM-006,COM-007 --format json --fail-on never \
    "$WORK/$capture.pcap" >"$WORK/$capture-enabled.json"
  "$NCSERVO" validate --enable COM-006,COM-007 --limit cycle_jitter_percent=1,return_latency_us=30 \
    --format json --fail-on never "$WORK/$capture.pcap" >"$WORK/$capture-tight.json"
  python3 - "$WORK/$capture-enabled.json" "$WORK/$capture-tight.json" <<'PY' || fail "$capture: COM-006/COM-007"
import json, sys
rules = lambda p: [f["rule"] for f in json.load(open(p))["captures"][0]["findings"]]
quiet, tight = rules(sys.argv[1]), rules(sys.argv[2])
assert not {"COM-006", "COM-007"} & set(quiet), quiet
assert tight.count("COM-007") == 1 and tight.count("COM-006") >= 1, tight
PY
done

# decode --timing prints the text report's timing block on standard error.
for capture in "$WORK/late.pcap" "$WORK/jitter-esl.pcap"; do
  "$NCSERVO" validate --fail-on never "$capture" | sed -n '/^timing (/,/^  worst cycle/p' >"$WORK/validate.txt"
  "$NCSERVO" decode --timing "$capture" 2>&1 >/dev/null | sed -n '/timing (/,/^  worst cycle/p' |
    sed "s|^ncservo: $capture: ||" >"$WORK/decode.txt"
  [ -s "$WORK/validate.txt" ] || fail "$capture: no timing block in the text report"
  diff "$WORK/validate.txt" "$WORK/decode.txt" || fail "$capture: decode --timing differs from validate"
done
echo "timing_truth: late, lost, latency and jitter as injected, through capture and probe timestamps; COM-002 tells late from lost"
