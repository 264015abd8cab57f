#!/usr/bin/env bash
# real_captures.sh SRC BUILD
# Over real EtherCAT captures from other people's hardware (none holds a servo of this protocol),
# tshark with the plugin exits 0, prints nothing on stderr and shows no axis field, the only
# NC-Servo items are the bus findings `ncservo validate` reports on the same frames and what the
# slaves said where validate lists it (docs/drive-messages.md), validate
# ends NO SERVO (exit 4; 0 with --allow-empty), and `ncservo decode` finds no axis, says so and
# exits 4 too.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_path "$REAL_CAPTURES" "real captures"
real=$REAL_CAPTURES
count=0
for capture in "$real"/*.pcap "$real"/*.pcapng "$real"/*.cap; do
  [ -f "$capture" ] || continue
  count=$((count + 1))
  cp "$capture" "$WORK/capture"
  chmod a+r "$WORK/capture"
  tshark_fields "$WORK/capture" "$WORK/out.tsv"
  if cut -f2- "$WORK/out.tsv" | grep -q '[^[:space:]]'; then
    fail "$(basename "$capture"): ncservo fields shown: $(cut -f2- "$WORK/out.tsv" | grep -m1 '[^[:space:]]')"
  fi
  "$TSHARK" "$PLUGIN" -2 -r "$WORK/capture" -V >"$WORK/verbose.txt" 2>"$WORK/err.txt" || fail "tshark -V exit $?"
  [ ! -s "$WORK/err.txt" ] || fail "$(basename "$capture"): stderr: $(head -3 "$WORK/err.txt")"
  # The only NC-Servo items are bus findings (ESM-*, COM-*) and what slaves said, on the frames
  # where the validator reports them.
  "$TSHARK" "$PLUGIN" -2 -r "$WORK/capture" -Y ncservo -T fields -e frame.number >"$WORK/plugin.txt"
  set +e
  "$NCSERVO" validate --format json --fail-on never "$WORK/capture" >"$WORK/report.json"
  rc=$?
  "$NCSERVO" validate --format json --fail-on never --allow-empty "$WORK/capture" >/dev/null
  allowed=$?
  set -e
  # no servo: nothing of this protocol was checked (exit 4, docs/cli.md)
  [ $rc = 4 ] || fail "$(basename "$capture"): validate exit $rc, expected 4 (no servo)"
  [ $allowed = 0 ] || fail "$(basename "$capture"): validate --allow-empty exit $allowed"
  python3 - "$WORK/report.json" "$WORK/plugin.txt" <<'PY' || fail "$(basename "$capture"): plugin and validator disagree"
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]
# The verdict describes the capture (docs/cli.md#verdicts): a bus error found is a FAIL.
errors = any(f["severity"] == "error" for f in c["findings"])
assert c["verdict"] == ("fail" if errors else "no servo"), c["verdict"]
assert "no servo of this protocol" in c["reason"], c["reason"]
assert all(f["rule"].split("-")[0] in ("ESM", "COM") and f["axis"] is None for f in c["findings"]), c["findings"]
# ... and what the slaves said (docs/drive-messages.md: the SOEM and Beckhoff start-ups' SDOs), on
# the frames that carried it.
said = [m["frame"] for m in c["drive_messages"]] + [e["frame"] for e in c["esc_errors"]] + \
    [f["frame"] for f in c["link_faults"]]
frames = sorted({f["frame"] for f in c["findings"]} | set(said))
shown = sorted({int(l) for l in open(sys.argv[2]) if l.strip()})
assert frames == shown, (frames, shown)
PY
  rc=0
  "$NCSERVO" decode "$WORK/capture" >"$WORK/decode.csv" 2>"$WORK/decode.err" || rc=$?
  [ $rc = 4 ] || fail "decode exit $rc, expected 4 (no servo, as validate)"
  [ "$(wc -l <"$WORK/decode.csv")" = 1 ] || fail "$(basename "$capture"): decode found rows"
  grep -q "no servo of this protocol found" "$WORK/decode.err" || fail "no plain message"
  echo "ok $(basename "$capture")"
done
[ $count -ge 1 ] || fail "no capture found"
