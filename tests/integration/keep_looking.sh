#!/usr/bin/env bash
# keep_looking.sh SRC BUILD
# Inference that keeps looking (docs/layout.md#keep-looking): axes enabled only after the first
# window are still found, the report says where the layout became certain and which frames were
# not judged; a capture that never becomes certain is NO SERVO with the reason; `decode --layout`
# on a capture where inference refuses exits 4 and writes valid TOML.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
ZERO="$SRC/tests/tools/zero_lrw_capture.py"

# 6000 cycles of zeros (12000 frames: no layout can be told from them, not even from the
# structure), then a 4-axis session: the layout becomes certain in a later window. The zeros are
# then judged with that layout (their WKC 3 against the servos' 12 gives COM-001 and COM-005), so
# only the layout's fields are checked here.
python3 "$ZERO" "$WORK/zero-start.pcap" 6000 200
python3 "$GEN" --axes 4 --cycles 20000 -o "$WORK/session.pcap" >/dev/null
require_program mergecap
mergecap -a -F pcap -w "$WORK/late.pcap" "$WORK/zero-start.pcap" "$WORK/session.pcap"
rc=0
"$NCSERVO" validate --format json "$WORK/late.pcap" >"$WORK/out" 2>"$WORK/err" || rc=$?
[ "$rc" -le 1 ] || fail "late layout: exit $rc: $(head -3 "$WORK/err")"
python3 - "$WORK/out" <<'PY' || fail "late layout json"
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]
layout = c["layout"]
assert layout["source"] == "inferred" and len(layout["axes"]) == 4, layout
assert layout["inference_windows"] > 1 and layout["certain_at_frame"] > 12000, layout
u = layout["unjudged_before_certain"]
assert u["frames"] == 0 or (u["first_frame"] == 1 and u["last_frame"] < layout["certain_at_frame"]), u
PY
rc=0
"$NCSERVO" validate "$WORK/late.pcap" >"$WORK/out" 2>&1 || rc=$?
[ "$rc" -le 1 ] || fail "late layout text: exit $rc"
grep -q "^  layout certain at frame [0-9]*, after [0-9]* cycles in [0-9]* windows of evidence; frames before the layout was certain, not judged: [0-9]*" "$WORK/out" ||
  fail "text: $(grep -i certain "$WORK/out")"
echo "ok layout certain after the first window"

# Zeros only, over several windows: never certain.
python3 "$ZERO" "$WORK/zero.pcap" 13000
rc=0
"$NCSERVO" validate "$WORK/zero.pcap" >"$WORK/out" 2>&1 || rc=$?
[ "$rc" = 4 ] || fail "zeros: exit $rc"
grep -q "^NO SERVO: .*the layout never became certain over the whole capture (13000 cycles in 4 windows of evidence)" "$WORK/out" ||
  fail "zeros: $(grep 'NO SERVO' "$WORK/out")"
echo "ok never certain"

# decode --layout where inference refuses: exit 4, valid TOML with no axis.
python3 "$ZERO" "$WORK/short.pcap" 3000
rc=0
"$NCSERVO" decode --layout "$WORK/short.pcap" >"$WORK/layout.toml" 2>/dev/null || rc=$?
[ "$rc" = 4 ] || fail "decode --layout refused: exit $rc"
python3 -c 'import sys, tomllib; t = tomllib.load(open(sys.argv[1], "rb")); assert "axis" not in t, t' \
  "$WORK/layout.toml" || fail "decode --layout: not TOML: $(cat "$WORK/layout.toml")"
grep -q "^# layout source: none, 0 axes" "$WORK/layout.toml" || fail "no reason: $(head -2 "$WORK/layout.toml")"
echo "ok decode --layout refused"
