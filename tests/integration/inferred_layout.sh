#!/usr/bin/env bash
# inferred_layout.sh SRC BUILD: the layout inferred from the cyclic traffic (docs/protocol.md §9.4).
# On simulated captures without a start-up, `validate` with no configuration reports exactly the
# findings it reports with the simulator's layout file, frame for frame, and so does tshark -2
# with the plugin (every PDO field and every expert item of every frame); on every real capture
# nothing is inferred and validate exits 4 (or 1 where a bus finding fails it).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

rows=(
  "1 axis|--axes 1 --seed 21"
  "3 axes, outputs first|--axes 3 --seed 22"
  "8 axes, outputs first, lossy|--axes 8 --loss 0.01 --seed 23"
  "5 axes among 3 terminals, interleaved|--axes 5 --io-slaves 3 --layout interleaved --seed 24"
  "ready mode 1|--axes 4 --ready-mode 1 --seed 25"
)
for row in "${rows[@]}"; do
  name=${row%%|*}
  read -r -a options <<<"${row#*|}"
  cap="$WORK/capture.pcap"
  "$NCSERVO" simulate --scenario commissioning --duration 2 --no-startup "${options[@]}" -o "$cap" \
    --layout-config "$WORK/layout.toml" 2>/dev/null
  chmod a+r "$cap" "$WORK/layout.toml"
  "$NCSERVO" validate --format jsonl --fail-on never "$cap" >"$WORK/inferred.jsonl" ||
    fail "$name: validate exit $?"
  "$NCSERVO" validate --format jsonl --fail-on never --config "$WORK/layout.toml" "$cap" \
    >"$WORK/configured.jsonl" || fail "$name: validate --config exit $?"
  cmp -s "$WORK/inferred.jsonl" "$WORK/configured.jsonl" ||
    fail "$name: findings differ: $(diff "$WORK/inferred.jsonl" "$WORK/configured.jsonl" | head -5)"
  "$NCSERVO" validate --fail-on never "$cap" | grep -q "^layout: inferred, " ||
    fail "$name: layout source is not 'inferred'"
  tshark_fields "$cap" "$WORK/inferred.tsv" -e _ws.expert.message
  tshark_fields "$cap" "$WORK/configured.tsv" -o "ncservo.config:$WORK/layout.toml" -e _ws.expert.message
  cmp -s "$WORK/inferred.tsv" "$WORK/configured.tsv" ||
    fail "$name: tshark -2 fields differ: $(diff "$WORK/inferred.tsv" "$WORK/configured.tsv" | head -5)"
done

# Only the cycles before any axis is enabled: refused as ambiguous, nothing decoded.
"$NCSERVO" simulate --scenario commissioning --duration 1 --no-startup --axes 2 --seed 26 \
  -o "$WORK/one.pcap" 2>/dev/null
editcap -r "$WORK/one.pcap" "$WORK/idle.pcap" 1-150
set +e
"$NCSERVO" validate "$WORK/idle.pcap" >"$WORK/idle.txt" 2>&1
rc=$?
set -e
[ $rc = 4 ] || fail "idle capture: exit $rc, expected 4"
grep -q "ambiguous" "$WORK/idle.txt" || fail "idle capture: no 'ambiguous' message: $(grep NO "$WORK/idle.txt")"

echo "inferred_layout: the inferred layout reports what the exact configuration reports"

# The real captures last: without them the cases above have run, and the test says it skipped these.
require_path "$REAL_CAPTURES" "real captures" "the simulated cases passed"
for capture in "$REAL_CAPTURES"/*.pcap* "$REAL_CAPTURES"/*.cap; do
  set +e
  "$NCSERVO" validate --format json "$capture" >"$WORK/real.json" 2>/dev/null
  rc=$?
  set -e
  [ $rc = 4 ] || [ $rc = 1 ] || fail "$(basename "$capture"): exit $rc, expected 4 (or 1)"
  python3 -c 'import json,sys; c=json.load(open(sys.argv[1]))["captures"][0]; assert not c["layout"]["axes"], c["layout"]' \
    "$WORK/real.json" || fail "$(basename "$capture"): a servo was inferred"
done
echo "inferred_layout: nothing inferred on the real captures"
