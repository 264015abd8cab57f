#!/usr/bin/env bash
# read_thread.sh SRC BUILD: a capture read and walked on a thread of its own, judged on another
# (`--read-thread on`, docs/cli.md#two-threads), gives the bytes one thread gives (`off`): every
# validate format (text on standard output, the others as --report files), the messages on
# standard error and the exit status; decode's CSV and diff alike. Over the bundled captures, the
# real ones (when present), hostile files (tests/tools/hostile_captures.py), a long capture of
# many batches, compressed, cut mid-record (the read error after the frames before it), standard
# input, a time window, and several captures with --jobs; decode's VCD, --layout and --timing.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
cd "$WORK"

captures=("$SRC"/captures/*.pcap "$SRC"/captures/*.pcapng)
if [ -d "$REAL_CAPTURES" ]; then
  for capture in "$REAL_CAPTURES"/*.pcap* "$REAL_CAPTURES"/*.cap; do
    [ -f "$capture" ] && captures+=("$capture")
  done
fi
python3 "$GEN" --axes 2 --cycles 200 -o two-axes
python3 "$SRC/tests/tools/hostile_captures.py" two-axes hostile
for capture in hostile/*; do captures+=("$capture"); done
"$NCSERVO" simulate --scenario faults --axes 6 --loss 0.01 --seed 5 -o long.pcapng 2>/dev/null
"$NCSERVO" simulate --scenario faults --axes 4 --seed 2 -o long.pcapng.zst 2>/dev/null
"$NCSERVO" simulate --scenario incidents --axes 4 --seed 4 -o incidents.pcap.gz 2>/dev/null
size=$(stat -c %s long.pcapng)
head -c $((size * 2 / 3 + 5)) long.pcapng >cut.pcapng
captures+=(long.pcapng long.pcapng.zst incidents.pcap.gz cut.pcapng missing.pcap)

formats=$("$NCSERVO" validate --help | sed -n 's/.*--format TEXT:{\([^}]*\)}.*/\1/p' | tr , ' ')
[ -n "$formats" ] || fail "no formats in validate --help"

# run NAME MODE ARGS...: validate with every format, then decode; what each wrote in NAME.MODE.*
run() {
  local name=$1 mode=$2
  shift 2
  local reports=() format rc=0
  for format in $formats; do
    [ "$format" = text ] || reports+=(--report "$format:$name.$mode.$format")
  done
  "$NCSERVO" validate --read-thread "$mode" --fail-on never "${reports[@]}" "$@" \
    >"$name.$mode.out" 2>"$name.$mode.err" || rc=$?
  echo "$rc" >"$name.$mode.rc"
}
# same NAME: the two modes wrote the same files
same() {
  local name=$1 f
  for f in "$name".off.*; do
    [ -e "$f" ] || continue
    cmp -s "$f" "${f/.off./.on.}" ||
      fail "$name: ${f#"$name".off.} differs with --read-thread on: $(diff "$f" "${f/.off./.on.}" | head -5)"
  done
}

n=0
for capture in "${captures[@]}"; do
  n=$((n + 1))
  for mode in off on; do
    run "c$n" "$mode" "$capture"
    # A GiB of zero-length records takes seconds: validate reads them, decode need not as well.
    [ "$(basename "$capture")" = huge-sparse ] && continue
    rc=0
    "$NCSERVO" decode --read-thread "$mode" "$capture" >"d$n.$mode.csv" 2>"d$n.$mode.err" || rc=$?
    echo "$rc" >"d$n.$mode.rc"
  done
  same "c$n"
  same "d$n"
  echo "ok $(basename "$capture") (validate exit $(cat "c$n.off.rc"))"
done
grep -q "cut.pcapng.*(the frames before it were analysed)" c*.off.err ||
  fail "the cut capture gave no read error"

# Standard input, a time window, several captures one at a time and two at a time, diff.
for mode in off on; do
  run stdin "$mode" - <long.pcapng
  run window "$mode" --from 0.5 --to 2.5 long.pcapng
  run jobs1 "$mode" --jobs 1 long.pcapng "$SRC/captures/faults-4axis.pcap" cut.pcapng
  run jobs2 "$mode" --jobs 2 long.pcapng "$SRC/captures/faults-4axis.pcap" cut.pcapng
  rc=0
  "$NCSERVO" diff --read-thread "$mode" "$SRC/captures/faults-4axis.pcap" long.pcapng \
    >"diff.$mode.out" 2>"diff.$mode.err" || rc=$?
  echo "$rc" >"diff.$mode.rc"
  "$NCSERVO" decode --read-thread "$mode" --format vcd long.pcapng >"vcd.$mode.out" 2>"vcd.$mode.err"
  "$NCSERVO" decode --read-thread "$mode" --layout long.pcapng >"layout.$mode.out" 2>"layout.$mode.err"
  "$NCSERVO" decode --read-thread "$mode" --timing --from 1 long.pcapng >"timing.$mode.out" \
    2>"timing.$mode.err"
done
for name in stdin window jobs1 jobs2 diff vcd layout timing; do same "$name"; done
for f in jobs1.off.*; do
  cmp -s "$f" "${f/jobs1/jobs2}" || fail "--jobs 2 differs from --jobs 1: ${f#jobs1.off.}"
done

rc=0
"$NCSERVO" validate --read-thread sometimes long.pcapng >/dev/null 2>err || rc=$?
[ "$rc" = 2 ] || fail "--read-thread sometimes: exit $rc"
grep -q "sometimes is not one of {off,on,auto}" err || fail "--read-thread sometimes: $(cat err)"
echo PASS
