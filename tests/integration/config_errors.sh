#!/usr/bin/env bash
# config_errors.sh SRC BUILD
# A bad configuration file ends with exit 2 and a message naming the file, the line and the key;
# in Wireshark it is reported and nothing crashes.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
python3 "$GEN" --axes 2 --cycles 200 -o "$WORK/capture"
printf 'default_layout = true\n\n[[axis]]\nname = "X"\noutputs = "not a number"\n' >"$WORK/bad.toml"
chmod a+r "$WORK"/*
set +e
"$NCSERVO" decode --config "$WORK/bad.toml" "$WORK/capture" >/dev/null 2>"$WORK/err.txt"
rc=$?
set -e
[ $rc = 2 ] || fail "bad config: exit $rc, expected 2"
grep -qF "$WORK/bad.toml:5: key 'axis[0].outputs'" "$WORK/err.txt" || fail "message: $(cat "$WORK/err.txt")"
set +e
"$NCSERVO" decode --config "$WORK/missing.toml" "$WORK/capture" >/dev/null 2>"$WORK/err2.txt"
rc=$?
set -e
[ $rc = 2 ] || fail "missing config: exit $rc, expected 2"
grep -qF "$WORK/missing.toml" "$WORK/err2.txt" || fail "missing config message: $(cat "$WORK/err2.txt")"

# Two axes on the same PDO bytes (Y's outputs inside X's, both at the same inputs).
printf '[[axis]]\nname = "X"\noutputs = 0x10000\ninputs = 0x10100\n\n[[axis]]\nname = "Y"\noutputs = 0x10004\ninputs = 0x10100\n' >"$WORK/overlap.toml"
set +e
"$NCSERVO" validate --config "$WORK/overlap.toml" "$WORK/capture" >/dev/null 2>"$WORK/err3.txt"
rc=$?
set -e
[ $rc = 2 ] || fail "overlapping axes: exit $rc, expected 2"
grep -qF "$WORK/overlap.toml:8: key 'axis[1].outputs': overlaps axis 'X'" "$WORK/err3.txt" ||
  fail "overlap message: $(cat "$WORK/err3.txt")"

# tshark reports the bad preference file and keeps running.
set +e
"$TSHARK" "$PLUGIN" -r "$WORK/capture" -o "ncservo.config:$WORK/bad.toml" -c 1 >/dev/null 2>"$WORK/ts.err"
rc=$?
set -e
[ $rc = 0 ] || fail "tshark exit $rc with a bad config"
grep -qF "bad.toml:5: key 'axis[0].outputs'" "$WORK/ts.err" || fail "tshark message: $(cat "$WORK/ts.err")"
echo "config_errors: exit 2 with file, line and key"
