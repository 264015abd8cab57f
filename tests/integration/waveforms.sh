#!/usr/bin/env bash
# waveforms.sh SRC BUILD
# `ncservo decode --format vcd` on the bundled captures and on simulated ones (faults,
# image styles, a probe, returned copies only, lost returns): every value change agrees with
# `decode --format jsonl` and the findings with `validate --format jsonl` (check_vcd.py);
# vcd2fst accepts every VCD and fst2vcd's reading of it agrees too; GTKWave (under Xvfb) opens
# the save file with the signals it names; --axis chooses the scopes; a failed write is an error.
# A missing tool or /dev/full: exit 77 with the reason (under CI: fails).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
CHECK_VCD="$SRC/tests/tools/check_vcd.py"
require_program vcd2fst fst2vcd

captures=("$SRC"/captures/*.pcap "$SRC"/captures/*.pcapng)
sim() {
  local name=$1
  shift
  "$NCSERVO" simulate "$@" -o "$WORK/$name" 2>/dev/null || fail "simulate $* exited $?"
  captures+=("$WORK/$name")
}
sim faults-8axis.pcap --scenario faults --axes 8
sim injected.pcapng --axes 3 --duration 6 --fault SE-001:0 --fault ZP-001:1 --fault EC-002:2 --fault COM-001 --fault ESM-001:1
sim etherlab-probe.pcapng --image etherlab --probe esl --axes 2 --fault SEW-001:1
sim twincat.pcap --image twincat --axes 5 --no-startup --fault RDY-001:4
sim lossy.pcap --axes 4 --loss 0.02 --seed 3
python3 "$GEN" --axes 3 --copies returned --cycles 400 -o "$WORK/returned.pcap"
python3 "$GEN" --axes 2 --copies master --cycles 300 -o "$WORK/master.pcap"
python3 "$GEN" --axes 4 --inject SE-001@0.2:1 --inject EC-001@0.5:2 --findings "$WORK/gen.json" -o "$WORK/gen-lost.pcapng" --format pcapng
captures+=("$WORK/returned.pcap" "$WORK/master.pcap" "$WORK/gen-lost.pcapng")

for capture in "${captures[@]}"; do
  name=$(basename "$capture")
  out="$WORK/$name"
  "$NCSERVO" decode --format vcd "$capture" -o "$out.vcd" 2>"$WORK/err" || fail "$name: decode vcd exited $?: $(cat "$WORK/err")"
  [ -s "$out.gtkw" ] || fail "$name: no save file beside $out.vcd"
  "$NCSERVO" decode --format jsonl "$capture" >"$out.jsonl" 2>/dev/null || fail "$name: decode jsonl exited $?"
  set +e
  "$NCSERVO" validate --format jsonl --fail-on never --allow-empty "$capture" >"$out.findings" 2>/dev/null
  rc=$?
  set -e
  [ $rc = 0 ] || [ $rc = 3 ] || fail "$name: validate exited $rc"
  vcd2fst "$out.vcd" "$out.fst" >"$WORK/err" 2>&1 || fail "$name: vcd2fst exited $?: $(cat "$WORK/err")"
  fst2vcd "$out.fst" >"$out.back.vcd" 2>"$WORK/err" || fail "$name: fst2vcd exited $?: $(cat "$WORK/err")"
  # The VCD, then the one read back from FST, each against jsonl.
  python3 "$CHECK_VCD" "$out.vcd" "$out.jsonl" "$out.findings" "$out.back.vcd" ||
    fail "$name: a VCD (decode's, or fst2vcd's of its FST) and jsonl differ"
done

# --axis: by name and by index; an axis that is not there is a usage error.
faults="$SRC/captures/faults-4axis.pcap"
"$NCSERVO" decode --format vcd --axis axis1,3 "$faults" -o "$WORK/two.vcd"
scopes=$(grep -o '^\$scope module [a-z0-9_]* ' "$WORK/two.vcd" | awk '{print $3}' | grep -v -E '^(bus|scw|ssw|sew|actpos)$' | tr '\n' ' ')
[ "$scopes" = "axis1 axis3 " ] || fail "--axis axis1,3 wrote the scopes: $scopes"
"$NCSERVO" decode --format jsonl --axis 2 "$faults" | python3 -c '
import json, sys
axes = {json.loads(line)["axis"] for line in sys.stdin}
assert axes == {2}, axes' || fail "decode jsonl --axis 2 wrote other axes"
set +e
"$NCSERVO" decode --format vcd --axis axis9 "$faults" -o "$WORK/none.vcd" 2>"$WORK/err"
rc=$?
set -e
[ $rc = 2 ] || fail "--axis axis9: exit $rc, expected 2"
grep -q "axis9: no such axis" "$WORK/err" || fail "--axis axis9: $(cat "$WORK/err")"

# A failed write is an error, not a short VCD (the text is written on a thread of its own).
[ -w /dev/full ] || skip "/dev/full is not writable (the full-disk case)"
set +e
"$NCSERVO" decode --format vcd "$WORK/faults-8axis.pcap" >/dev/full 2>"$WORK/err"
rc=$?
set -e
[ $rc = 2 ] || fail "decode vcd to a full disk: exit $rc, expected 2"
grep -q "^ncservo: standard output: cannot write: No space left on device$" "$WORK/err" ||
  fail "decode vcd to a full disk: $(cat "$WORK/err")"

# GTKWave opens the save file alone, from elsewhere, and shows every signal it names (last: the
# cases above have run when GTKWave or Xvfb is missing, and the test says it skipped this one).
require_program gtkwave xvfb-run
cat >"$WORK/shown.tcl" <<'TCL'
puts "SHOWN [llength [gtkwave::getDisplayedSignals]]"
gtkwave::/File/Quit
TCL
mkdir "$WORK/moved"
cp "$WORK/faults-4axis.pcap.vcd" "$WORK/faults-4axis.pcap.gtkw" "$WORK/moved/"
rm "$WORK/faults-4axis.pcap.vcd"
named=$(grep -c -v -E '^(\[|@|-)' "$WORK/moved/faults-4axis.pcap.gtkw")
shown=$(cd / && timeout 120 xvfb-run -a gtkwave "$WORK/moved/faults-4axis.pcap.gtkw" \
  -S "$WORK/shown.tcl" 2>&1 | sed -n 's/^SHOWN //p')
[ "$shown" = "$named" ] || fail "GTKWave shows ${shown:-no} signals of the $named the save file names"
[ "$named" = 53 ] || fail "the save file names $named signals, expected 1 + 4 axes x 13"
echo "waveforms: ${#captures[@]} captures agree with decode and validate; vcd2fst reads them all"
