#!/usr/bin/env bash
# capture_segments.sh SRC BUILD: captures appended (`mergecap -a`: the timestamps jump back) or
# paused (an hour between two parts) are segments (docs/cli.md, docs/protocol.md §8): every
# finding of the faulty part is reported on the same frames, offset by the part before it, with
# the same rule and axis, as when it is validated alone; an hour's pause gives no finding.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

# findings CAPTURE OFFSET: "RULE AXIS FRAME" per finding, frames less OFFSET, those below 1 dropped.
findings() {
  "$NCSERVO" validate --format jsonl --fail-on never "$1" | python3 -c '
import json, sys
offset = int(sys.argv[1])
for line in sys.stdin:
    d = json.loads(line)
    if "rule" in d and d["frame"] - offset >= 1:
        print(d["rule"], d["axis"], d["frame"] - offset)' "$2"
}
frames() { "$NCSERVO" validate --format json --fail-on never "$1" | python3 -c '
import json, sys; print(json.load(sys.stdin)["captures"][0]["frames"])'; }

# same_as_alone NAME FAULTY MERGED OFFSET: the merged capture's findings from OFFSET on are the
# faulty part's. A slave finding before the layout is known names no axis alone; appended, the
# layout is known (it carries on): the axis is compared only where the part alone names one.
same_as_alone() {
  local name=$1 faulty=$2 merged=$3 offset=$4
  findings "$faulty" 0 >"$WORK/alone.txt"
  findings "$merged" "$offset" >"$WORK/merged.txt"
  [ -s "$WORK/alone.txt" ] || fail "$name: the faulty part alone has no finding"
  python3 - "$WORK/alone.txt" "$WORK/merged.txt" <<'PY' || fail "$name: findings differ"
import sys
alone = sorted(tuple(l.split()) for l in open(sys.argv[1]))
merged = sorted(tuple(l.split()) for l in open(sys.argv[2]))
ok = len(alone) == len(merged) and all(
    a[0] == m[0] and a[2] == m[2] and (a[1] == "None" or a[1] == m[1])
    for a, m in zip(sorted(alone, key=lambda f: (f[2], f[0])), sorted(merged, key=lambda f: (f[2], f[0]))))
if not ok:
    print("alone: ", [" ".join(f) for f in alone], file=sys.stderr)
    print("merged:", [" ".join(f) for f in merged], file=sys.stderr)
    sys.exit(1)
PY
}

"$NCSERVO" simulate --scenario commissioning -o "$WORK/clean.pcap" 2>/dev/null
"$NCSERVO" simulate --scenario faults -o "$WORK/faulty.pcap" 2>/dev/null
CLEAN_FRAMES=$(frames "$WORK/clean.pcap")

mergecap -a -w "$WORK/clean_faulty.pcap" "$WORK/clean.pcap" "$WORK/faulty.pcap"
same_as_alone "simulated clean + faulty" "$WORK/faulty.pcap" "$WORK/clean_faulty.pcap" "$CLEAN_FRAMES"
mergecap -a -w "$WORK/faulty_clean.pcap" "$WORK/faulty.pcap" "$WORK/clean.pcap"
same_as_alone "simulated faulty + clean" "$WORK/faulty.pcap" "$WORK/faulty_clean.pcap" 0

BUNDLED_CLEAN="$SRC/captures/commissioning-4axis.pcap"
BUNDLED_FAULTY="$SRC/captures/faults-4axis.pcap"
mergecap -a -w "$WORK/bundled_cf.pcap" "$BUNDLED_CLEAN" "$BUNDLED_FAULTY"
same_as_alone "bundled clean + faulty" "$BUNDLED_FAULTY" "$WORK/bundled_cf.pcap" \
  "$(frames "$BUNDLED_CLEAN")"
mergecap -a -w "$WORK/bundled_fc.pcap" "$BUNDLED_FAULTY" "$BUNDLED_CLEAN"
same_as_alone "bundled faulty + clean" "$BUNDLED_FAULTY" "$WORK/bundled_fc.pcap" 0

# Two segments, listed in every report that lists them.
"$NCSERVO" validate --format json "$WORK/clean_faulty.pcap" >"$WORK/cf.json" || true
python3 - "$WORK/cf.json" "$CLEAN_FRAMES" <<'PY' || fail "clean + faulty: JSON timing.segments"
import json, sys
segments = json.load(open(sys.argv[1]))["captures"][0]["timing"]["segments"]
n = int(sys.argv[2])
assert len(segments) == 2, segments
assert segments[0]["first_frame"] == 1 and segments[1]["first_frame"] == n + 1, segments
assert segments[1]["start"] == 0.0, segments  # the second part's own time: it went back
PY

# An hour's pause between two clean parts: no finding at all, two segments.
editcap -t 3600 "$WORK/clean.pcap" "$WORK/clean_later.pcap"
mergecap -a -w "$WORK/paused.pcap" "$WORK/clean.pcap" "$WORK/clean_later.pcap"
"$NCSERVO" validate --format jsonl --fail-on info "$WORK/paused.pcap" >"$WORK/paused.jsonl" ||
  fail "an hour's pause: exit $?: $(head -3 "$WORK/paused.jsonl")"
python3 - "$WORK/paused.jsonl" <<'PY' || fail "an hour's pause: $(cat "$WORK/paused.jsonl")"
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
assert not any("rule" in l for l in lines), "findings"
segments = [l for l in lines if "segments" in l][0]["segments"]
assert len(segments) == 2 and segments[1]["start"] == 3600.0, segments
PY
"$NCSERVO" validate "$WORK/paused.pcap" >"$WORK/paused.txt" || fail "text: exit $?"
grep -q '^segments: 2' "$WORK/paused.txt" || fail "the text report lists no segments"
[ "$(grep -c '^  frames ' "$WORK/paused.txt")" = 2 ] || fail "the text report: one line per segment"
# capture_pause longer than the pause: one segment, and the pause is a gap.
"$NCSERVO" validate --format jsonl --timeout capture_pause=3600000 --fail-on never \
  "$WORK/paused.pcap" | grep '"COM-002"' >/dev/null || fail "capture_pause=3600000: the pause is no gap"
printf '[timeouts]\ncapture_pause = 3600000\n' >"$WORK/pause.toml"
"$NCSERVO" validate --format jsonl --config "$WORK/pause.toml" --fail-on never \
  "$WORK/paused.pcap" | grep '"COM-002"' >/dev/null || fail "[timeouts] capture_pause: not taken"
echo "capture_segments: appended and paused captures judged per segment"
