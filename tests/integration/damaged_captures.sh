#!/usr/bin/env bash
# damaged_captures.sh SRC BUILD
# Short PDO regions are marked malformed in Wireshark without a crash; a capture cut inside a
# record ends `ncservo decode` with exit 3 naming the file and the frame, after decoding what came
# before; hostile files (table below) give the documented exit code and a message naming the file.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
python3 "$GEN" --axes 8 --cycles 200 -o "$WORK/capture"
# Snap length 100: an 8-axis LRW (400 data bytes) keeps 7 RxPDOs and no TxPDO.
editcap -s 100 "$WORK/capture" "$WORK/snapped" >/dev/null
chmod a+r "$WORK"/*
"$TSHARK" "$PLUGIN" -2 -r "$WORK/snapped" -Y ncservo.malformed -T fields -e frame.number \
  >"$WORK/malformed.txt" 2>"$WORK/err.txt" || fail "tshark exit $? on a snapped capture"
[ ! -s "$WORK/err.txt" ] || fail "stderr: $(cat "$WORK/err.txt")"
[ "$(wc -l <"$WORK/malformed.txt")" = 400 ] || fail "expected all 400 frames marked, got $(wc -l <"$WORK/malformed.txt")"
# Frame 1 after the whole first pass (-c 1 would end the first pass, and so the learning window, there).
"$TSHARK" "$PLUGIN" -2 -r "$WORK/snapped" -T fields -E occurrence=a -e ncservo.axis -e ncservo.scw -Y "frame.number == 1" \
  >"$WORK/first.txt"
[ "$(cut -f1 "$WORK/first.txt")" = "0,1,2,3,4,5,6,7" ] || fail "axes: $(cat "$WORK/first.txt")"
[ "$(cut -f2 "$WORK/first.txt" | tr ',' '\n' | wc -l)" = 7 ] || fail "expected 7 RxPDOs: $(cat "$WORK/first.txt")"
"$NCSERVO" decode "$WORK/snapped" >"$WORK/snapped.csv" 2>"$WORK/snapped.err" || fail "decode exit $?"
# One summary line, not one per frame and axis: the cut frames, the first, every axis cut.
grep -q "PDO words not captured in 400 frames (first: frame 1) for .*axis7" "$WORK/snapped.err" || fail "no malformed message: $(head -2 "$WORK/snapped.err")"
[ "$(wc -l <"$WORK/snapped.err")" = 1 ] || fail "more than one line: $(head -3 "$WORK/snapped.err")"

# A capture cut in the middle of a record.
size=$(stat -c %s "$WORK/capture")
head -c $((size / 2 + 7)) "$WORK/capture" >"$WORK/cut"
set +e
"$NCSERVO" decode "$WORK/cut" >"$WORK/cut.csv" 2>"$WORK/cut.err"
rc=$?
set -e
[ $rc = 3 ] || fail "cut capture: exit $rc, expected 3"
grep -qE "$WORK/cut: frame [0-9]+: .*truncated" "$WORK/cut.err" || fail "cut message: $(cat "$WORK/cut.err")"
[ "$(wc -l <"$WORK/cut.csv")" -gt 100 ] || fail "frames before the damage were not decoded"

# Hostile files, one row each: what `ncservo validate` must exit with, a line its standard error
# must hold ("-": nothing on standard error), and how many frames its JSON report still counts.
# `ncservo decode` must give the same verdict (0 or 3) and message. Every run has a time limit and
# a memory bound (peak RSS), so a hang or a runaway allocation fails the row.
python3 "$GEN" --axes 2 --cycles 200 -o "$WORK/two-axes"
python3 "$SRC/tests/tools/hostile_captures.py" "$WORK/two-axes" "$WORK/hostile"
mkdir "$WORK/hostile/directory"
echo "hello" >"$WORK/hostile/not-a-capture"
after="(the frames before it were analysed)"
cases=(
  # file|exit|message on standard error|frames reported
  "missing|3|missing: cannot read capture: No such file or directory|0"
  "directory|3|directory: cannot read capture: is a directory|0"
  "empty|3|empty: cannot read capture: empty file|0"
  "not-a-capture|3|not-a-capture: cannot read capture: unknown file format|0"
  "truncated-global-header|3|cannot read capture: truncated dump file; tried to read 24 file header bytes, only got 9|0"
  "truncated-record-header|3|frame 101: truncated dump file; tried to read 16 header bytes, only got 9 $after|100"
  "truncated-record-data|3|frame 101: truncated dump file; tried to read 148 captured bytes, only got 24 $after|100"
  "caplen-above-snaplen|0|PDO words not captured in 50 frames (first: frame 2) for axis0|100"
  "caplen-above-record|3|frame 101: truncated dump file; tried to read 5148 captured bytes, only got 148 $after|100"
  "caplen-above-original|0|-|100"
  "absurd-caplen|3|frame 101: invalid packet capture length 4294967280, bigger than snaplen of 65535 $after|100"
  "absurd-snaplen|0|-|100"
  "zero-length-frames|0|-|200"
  "timestamps-backwards|0|-|400"
  "timestamp-after-2262|0|-|100"
  "pcapng-unknown-blocks|0|-|100"
  "pcapng-oversized-block|3|frame 101: pcapng block size 2147483632 > maximum 16777216 $after|100"
  "pcapng-short-block|3|frame 101: block in pcapng dump file has a length of 8 < 12 $after|100"
  "pcapng-mixed-link-types|0|-|200"  # read as Wireshark reads it: docs/cli.md#interfaces
  "pcapng-interface-out-of-range|3|frame 51: a packet arrived on interface 7, but there's no Interface Description Block for that interface $after|50"
  "huge-sparse|0|-|$((100 + (1 << 30) / 16))"
)
# run_bounded SECONDS MAX_RSS_MB OUT ERR COMMAND...: exit status of COMMAND; fails the test when it
# runs out of time or memory.
run_bounded() {
  python3 - "$@" <<'PY'
import resource, subprocess, sys
seconds, max_mb, out, err, command = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5:]
try:
    rc = subprocess.run(command, stdout=open(out, "wb"), stderr=open(err, "wb"), timeout=seconds).returncode
except subprocess.TimeoutExpired:
    sys.exit(f"FAIL: {' '.join(command)}: still running after {seconds} s")
peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
if peak_mb > max_mb:
    sys.exit(f"FAIL: {' '.join(command)}: peak RSS {peak_mb:.0f} MB > {max_mb} MB")
sys.exit(rc if rc >= 0 else 128 - rc)
PY
}
for row in "${cases[@]}"; do
  IFS='|' read -r name want message frames <<<"$row"
  file="$WORK/hostile/$name"
  set +e
  run_bounded 300 256 "$WORK/report.json" "$WORK/validate.err" \
    "$NCSERVO" validate --format json --fail-on never "$file"
  rc=$?
  set -e
  [ $rc = "$want" ] || fail "$name: validate exit $rc, expected $want: $(head -3 "$WORK/validate.err")"
  if [ "$message" = - ]; then
    [ ! -s "$WORK/validate.err" ] || fail "$name: unexpected message: $(head -3 "$WORK/validate.err")"
  else
    grep -qF "ncservo: $WORK/hostile/" "$WORK/validate.err" || fail "$name: message does not name the file: $(head -3 "$WORK/validate.err")"
    grep -qF -- "$message" "$WORK/validate.err" || fail "$name: expected '$message', got: $(head -3 "$WORK/validate.err")"
  fi
  got=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["captures"][0]["frames"])' "$WORK/report.json") ||
    fail "$name: no readable JSON report"
  [ "$got" = "$frames" ] || fail "$name: report counts $got frames, expected $frames"
  set +e
  run_bounded 300 256 /dev/null "$WORK/decode.err" "$NCSERVO" decode "$file"
  rc=$?
  set -e
  [ $rc = "$want" ] || fail "$name: decode exit $rc, expected $want: $(head -3 "$WORK/decode.err")"
  if [ "$message" != - ]; then
    grep -qF -- "${message% "$after"}" "$WORK/decode.err" || fail "$name: decode: expected '$message', got: $(head -3 "$WORK/decode.err")"
  fi
done
echo "damaged_captures: malformed marked, truncation reported, ${#cases[@]} hostile files handled"
