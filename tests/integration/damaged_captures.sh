#!/usr/bin/env bash
# damaged_captures.sh SRC BUILD
# Short PDO regions are marked malformed in Wireshark without a crash; a capture cut inside a
# record ends `ncservo decode` with exit 3 naming the file and the frame, after decoding what came
# before; a missing file or a non-capture is exit 3 with its name.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
python3 "$GEN" --axes 8 --cycles 200 -o "$WORK/capture"
# Snap length 100: an 8-axis LRW (400 data bytes) keeps 7 RxPDOs and no TxPDO.
editcap -s 100 "$WORK/capture" "$WORK/snapped" >/dev/null
chmod a+r "$WORK"/*
"$TSHARK" "$PLUGIN" -r "$WORK/snapped" -Y ncservo.malformed -T fields -e frame.number \
  >"$WORK/malformed.txt" 2>"$WORK/err.txt" || fail "tshark exit $? on a snapped capture"
[ ! -s "$WORK/err.txt" ] || fail "stderr: $(cat "$WORK/err.txt")"
[ "$(wc -l <"$WORK/malformed.txt")" = 400 ] || fail "expected all 400 frames marked, got $(wc -l <"$WORK/malformed.txt")"
"$TSHARK" "$PLUGIN" -r "$WORK/snapped" -T fields -E occurrence=a -e ncservo.axis -e ncservo.scw -c 1 \
  >"$WORK/first.txt"
[ "$(cut -f1 "$WORK/first.txt")" = "0,1,2,3,4,5,6,7" ] || fail "axes: $(cat "$WORK/first.txt")"
[ "$(cut -f2 "$WORK/first.txt" | tr ',' '\n' | wc -l)" = 7 ] || fail "expected 7 RxPDOs: $(cat "$WORK/first.txt")"
"$NCSERVO" decode "$WORK/snapped" >"$WORK/snapped.csv" 2>"$WORK/snapped.err" || fail "decode exit $?"
grep -q "frame 1: axis 7: RxPDO region cut short" "$WORK/snapped.err" || fail "no malformed message: $(head -2 "$WORK/snapped.err")"

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

for bad in "$WORK/missing.pcap" "$WORK/not-a-capture.txt" "$WORK"; do
  echo "hello" >"$WORK/not-a-capture.txt"
  set +e
  "$NCSERVO" decode "$bad" >/dev/null 2>"$WORK/bad.err"
  rc=$?
  set -e
  [ $rc = 3 ] || fail "$bad: exit $rc, expected 3"
  grep -qF "$bad" "$WORK/bad.err" || fail "$bad: message does not name the file: $(cat "$WORK/bad.err")"
done
echo "damaged_captures: malformed marked, truncation reported, bad files named"
