#!/usr/bin/env bash
# time_window.sh SRC BUILD: `--from/--to` (docs/cli.md) on validate and decode: a window around
# one finding of the faults capture gives that finding and no other; a window with no frame in it
# is NO SERVO (exit 4) and says why; --to before --from is a usage error.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
CAPTURE="$SRC/captures/faults-4axis.pcap"

"$NCSERVO" validate --format jsonl --fail-on never "$CAPTURE" >"$WORK/all.jsonl"
# Each row: a finding's rule, and a window around its time that holds no other finding.
while read -r rule from to; do
  rc=0
  "$NCSERVO" validate --format jsonl --fail-on never --from "$from" --to "$to" "$CAPTURE" \
    >"$WORK/window.jsonl" || rc=$?
  [ "$rc" = 0 ] || fail "$rule window $from..$to: exit $rc"
  python3 - "$WORK/all.jsonl" "$WORK/window.jsonl" "$rule" <<'PY' || fail "$rule window $from..$to"
import json, sys
whole = [json.loads(l) for l in open(sys.argv[1])]
got = [json.loads(l) for l in open(sys.argv[2])]
want = [(f["rule"], f["axis"], f["frame"], f["time"]) for f in whole if f.get("rule") == sys.argv[3]]
have = [(f["rule"], f["axis"], f["frame"], f["time"]) for f in got if "rule" in f]
assert have == want, f"{have} != {want}"
PY
done <<'ROWS'
COM-001 0.85 0.95
MSG-001 1.55 1.65
COM-002 2.15 2.25
ROWS

rc=0
"$NCSERVO" validate --from 100 --to 101 "$CAPTURE" >"$WORK/empty.txt" 2>&1 || rc=$?
[ "$rc" = 4 ] || fail "an empty window: exit $rc, expected 4"
grep -q 'no EtherCAT frame in the time window' "$WORK/empty.txt" || fail "an empty window: $(cat "$WORK/empty.txt")"
rc=0
"$NCSERVO" decode --from 100 "$CAPTURE" >/dev/null 2>"$WORK/decode.err" || rc=$?
[ "$rc" = 4 ] || fail "decode, an empty window: exit $rc, expected 4"
grep -q 'no EtherCAT frame in the time window' "$WORK/decode.err" || fail "decode: $(cat "$WORK/decode.err")"
rc=0
"$NCSERVO" validate --from 2 --to 1 "$CAPTURE" >/dev/null 2>&1 || rc=$?
[ "$rc" = 2 ] || fail "--to before --from: exit $rc, expected 2"

# decode prints the window's rows only, with the capture's own times.
"$NCSERVO" decode --format jsonl --from 1 --to 1.01 "$CAPTURE" >"$WORK/rows.jsonl"
python3 - "$WORK/rows.jsonl" <<'PY' || fail "decode --from 1 --to 1.01"
import json, sys
times = [json.loads(l)["time"] for l in open(sys.argv[1])]
assert times and all(1.0 <= t <= 1.01 for t in times), (times[:3], times[-3:])
PY
echo "time_window: --from/--to judge and decode only the window"
