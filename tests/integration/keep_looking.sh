#!/usr/bin/env bash
# keep_looking.sh SRC BUILD
# Inference that keeps looking (docs/layout.md#keep-looking): axes enabled only after the first
# window are still found, the report says where the layout became certain and which frames were
# not judged; a capture that never becomes certain is NO SERVO with the reason; `decode --layout`
# on a capture where inference refuses exits 4 and writes valid TOML.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
ZERO="$SRC/tests/tools/zero_lrw_capture.py"

# gen_capture enables axis 0 at 2 % of the cycles: after the 4096-cycle window here.
python3 "$GEN" --axes 4 --cycles 220000 -o "$WORK/late.pcap"
rc=0
"$NCSERVO" validate --format json "$WORK/late.pcap" >"$WORK/out" 2>"$WORK/err" || rc=$?
[ "$rc" = 0 ] || fail "late enables: exit $rc: $(head -3 "$WORK/err")"
python3 - "$WORK/out" <<'PY' || fail "late enables json"
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]
layout = c["layout"]
assert layout["source"] == "inferred" and len(layout["axes"]) == 4, layout
assert layout["inference_windows"] > 1 and layout["certain_at_frame"] > 8192, layout
u = layout["unjudged_before_certain"]
assert u["frames"] > 0 and u["first_frame"] == 1 and u["last_frame"] < layout["certain_at_frame"], u
assert c["verdict"] == "pass", c["verdict"]
PY
"$NCSERVO" validate "$WORK/late.pcap" >"$WORK/out" 2>&1 || fail "late enables text"
grep -q "^  layout certain at frame [0-9]*, after [0-9]* cycles in [0-9]* windows of evidence; frames before the layout was certain, not judged: [0-9]* (1–[0-9]*)$" "$WORK/out" ||
  fail "text: $(grep -i certain "$WORK/out")"
echo "ok axes enabled after the first window"

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
