#!/usr/bin/env bash
# monitor_live.sh SRC BUILD: `ncservo monitor` on one end of a veth pair while Debian's
# tcpreplay replays a simulated capture with faults into the other end, in a network namespace of
# its own. The live findings are the file's (same rule and axis); Ctrl-C ends with the report and
# the exit status; the flight recorder's pcapngs hold a comment for each recorded finding and, with
# a window that spans the run, validate to the same findings. Needs root (veth, namespaces) and
# tcpreplay: otherwise exit 77 with the reason (under CI: fails). A replay that stalled (the
# machine too busy for tcpreplay to keep the capture's timing: gaps the capture does not have)
# makes the timing rules see what was not there; the run is then repeated, and skipped (77, saying
# so, even under CI: nothing is missing) if it keeps stalling.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

[ "$(id -u)" = 0 ] || skip "needs root (veth pair, network namespace)"
require_program tcpreplay ip

veth_pair ncsm

cd "$WORK"
# 4 ms cycles: a replay a few milliseconds late is not a lost cycle.
"$NCSERVO" simulate --scenario faults --cycle-us 4000 -o faults.pcap 2>/dev/null
"$NCSERVO" validate --format jsonl --fail-on never faults.pcap >file.jsonl

# pairs FINDINGS.jsonl: the (rule, axis) pairs, one a line.
pairs() {
  python3 -c 'import json, sys
print("\n".join(sorted({"%s %s" % (j["rule"], j["axis"]) for j in map(json.loads, open(sys.argv[1])) if "rule" in j})))' "$1"
}
pairs file.jsonl >file.pairs

# gaps CAPTURE: the gaps between two frames that COM-002 would see (over 1.5 cycles, 6 ms), and
# the longest, in ms: "COUNT LONGEST".
gaps() {
  tshark -r "$1" -T fields -e frame.time_delta 2>/dev/null |
    awk '$1 > 0.006 { n++ } $1 > max { max = $1 } END { printf "%d %d\n", n, max * 1000 }'
}
read -r file_gaps file_gap < <(gaps faults.pcap)

# replay WINDOW: monitor with the recorder (window WINDOW s), the capture replayed, then Ctrl-C.
replay() {
  rm -rf rec && mkdir rec
  "$NCSERVO" monitor -i "$host" --format jsonl --record rec --record-window "$1" \
    >live.jsonl 2>live.err &
  local pid=$!
  sleep 1
  # A real-time policy keeps the replay on time on a busy machine (2 cores under ctest -j2 and
  # compilers). With it, tcpreplay's default timer busy-waits, and the kernel's real-time
  # throttling (sched_rt_runtime_us: 950 ms of each second) then stops it for 50 ms every
  # second, gaps the capture does not have; the nanosleep() timer sleeps instead. (The select()
  # one sleeps too in tcpreplay 4.4, Debian 12, but in 4.5, Debian 13, it does not wait at all.)
  ip netns exec "$ns" $realtime tcpreplay -q --preload-pcap --timer=nano -i "$peer" faults.pcap \
    >/dev/null
  sleep 0.5
  kill -INT "$pid"
  rc=0
  wait "$pid" || rc=$?
}

realtime="chrt -f 50"
$realtime true 2>/dev/null || { realtime=""; echo "note: no real-time policy allowed; replaying without"; }
stalled=""
for attempt in 1 2 3; do
  replay 10
  [ "$rc" = 1 ] || fail "monitor: exit $rc (findings of errors: 1): $(cat live.err)"
  grep -q "frames captured; dropped: 0 by the kernel" live.err || fail "no drop count: $(cat live.err)"
  recordings=(rec/*.pcapng)
  [ "${#recordings[@]}" = 1 ] || fail "a 10 s window over a 4 s run: ${#recordings[@]} recordings"
  read -r live_gaps gap < <(gaps "${recordings[0]}")
  pairs live.jsonl >live.pairs
  if cmp -s file.pairs live.pairs; then
    # The recording spans the run: it validates to the same findings.
    "$NCSERVO" validate --format jsonl --fail-on never "${recordings[0]}" >rec.jsonl
    pairs rec.jsonl >rec.pairs
    if cmp -s file.pairs rec.pairs; then stalled=""; break; fi
    recording_differs="$(diff file.pairs rec.pairs | tr '\n' ' ')"
    echo "attempt $attempt: live findings = the file's, the recording's differ: $recording_differs"
    stalled="the recording differs"
    continue
  fi
  # A replay late by half a cycle is a gap the capture does not have: a lost or late cycle that
  # ends an outage early or starts one (COM-002, COM-003, COM-005).
  if [ "$live_gaps" -le "$file_gaps" ]; then
    fail "live findings differ from the file's with no stall ($live_gaps gaps over 6 ms, the longest $gap ms; the file's: $file_gaps): $(diff file.pairs live.pairs)"
  fi
  stalled="tcpreplay stalled: $live_gaps gaps over 6 ms, the longest $gap ms (the capture's: $file_gaps, $file_gap ms)"
  echo "attempt $attempt: $stalled; findings differ: $(diff file.pairs live.pairs | tr '\n' ' ')"
done
[ "$stalled" != "the recording differs" ] ||
  fail "the recording's findings differ from the file's in every attempt: $recording_differs"
[ -z "$stalled" ] || { echo "SKIPPED: the machine is too busy to replay in time: $stalled"; exit 77; }
echo "ok live findings = the file's ($(wc -l <file.pairs) rule/axis pairs)"
echo "ok the recording validates to the same findings"
# The same frames give the same report: monitor's end of report against validate's of the
# recording (the frames the monitor judged), every object but the findings, apart from what only
# a live capture has (the interface's name, its clock's resolution).
"$NCSERVO" validate --format jsonl --fail-on never "${recordings[0]}" >rec.jsonl || true
python3 - live.jsonl rec.jsonl <<'PY' || fail "monitor's report differs from validate's on the same frames"
import json, sys
LIVE_ONLY = {"capture", "resolution_ns", "capture_dropped"}
def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if k not in LIVE_ONLY}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v
def summary(path):
    return [strip(j) for j in map(json.loads, open(path)) if "rule" not in j]
live, rec = summary(sys.argv[1]), summary(sys.argv[2])
for a, b in zip(live, rec):
    if a != b:
        print("live:      ", json.dumps(a)[:600]); print("validate:  ", json.dumps(b)[:600])
assert live == rec, f"{len(live)} live objects, {len(rec)} validate objects"
print(f"ok monitor's report = validate's on the recording ({len(live)} objects besides the findings)")
PY

# Short windows: a recording per group of findings, each recorded finding a comment on its frame.
replay 0.3
[ "$rc" = 1 ] || fail "monitor (short windows): exit $rc"
python3 - live.jsonl rec <<'PY' || fail "short windows"
import glob, json, subprocess, sys
severity = {"info": 0, "warning": 1, "error": 2}
live = [j for j in map(json.loads, open(sys.argv[1])) if "rule" in j and severity[j["severity"]] >= 1]
comments = []
files = sorted(glob.glob(sys.argv[2] + "/*.pcapng"))
assert len(files) > 1, f"{len(files)} recordings"
for f in files:
    out = subprocess.run(["tshark", "-r", f, "-T", "fields", "-e", "frame.comment", "-Y", "frame.comment",
                          "-E", "aggregator=\x1f"], capture_output=True, text=True).stdout
    comments += [c.split(" ")[0] for line in out.splitlines() for c in line.split("\x1f")]
assert sorted(comments) == sorted(j["rule"] for j in live), f"{len(comments)} comments, {len(live)} findings"
print(f"ok {len(files)} recordings hold the {len(live)} findings' comments")
PY

# Permission and interface errors name what is missing.
rc=0; "$NCSERVO" monitor -i no-such-if0 2>err || rc=$?
[ "$rc" = 3 ] && grep -q "no such interface" err || fail "bad interface: exit $rc: $(cat err)"
rc=0; setpriv --reuid=65534 --regid=65534 --clear-groups "$NCSERVO" monitor -i "$host" 2>err || rc=$?
[ "$rc" = 3 ] && grep -q CAP_NET_RAW err || fail "no permission: exit $rc: $(cat err)"
echo PASS
