#!/usr/bin/env bash
# capture_loss.sh SRC BUILD
# Capture loss is not bus loss (docs/timing.md "Capture loss"): master copies the simulator leaves
# out of the capture give no COM-002, COM-003 or COM-005, and the report counts exactly the ones
# left out; a pcapng whose interface statistics block says it dropped frames says so in its
# verdict line and its JSON, plain, gzip- or zstd-compressed or from standard input.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

"$NCSERVO" simulate --no-startup --axes 2 --duration 2 --capture-loss 0.05 --seed 7 \
  -o "$WORK/loss.pcap" 2>"$WORK/sim.txt" || fail "simulate: $(cat "$WORK/sim.txt")"
dropped=$(sed -n 's/.* \([0-9]*\) master copies left out of the capture/\1/p' "$WORK/sim.txt")
[ -n "$dropped" ] && [ "$dropped" -gt 0 ] || fail "no truth: $(cat "$WORK/sim.txt")"
"$NCSERVO" validate --format json --fail-on never "$WORK/loss.pcap" >"$WORK/loss.json"
python3 - "$WORK/loss.json" "$dropped" <<'PY' || fail "capture loss: $(head -c 800 "$WORK/loss.json")"
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]
rules = sorted({f["rule"] for f in c["findings"]})
assert not set(rules) & {"COM-002", "COM-003", "COM-005", "COM-004"}, rules
assert c["timing"]["master_copies_missing"] == int(sys.argv[2]), c["timing"]["master_copies_missing"]
assert c["timing"]["returned_copies_missing"] == 0, c["timing"]["returned_copies_missing"]
assert c["cycles"] == 2000, c["cycles"]
PY

# Without --capture-loss the capture is the one it always was.
"$NCSERVO" simulate --no-startup --axes 2 --duration 2 --seed 7 -o "$WORK/a.pcap" 2>/dev/null
"$NCSERVO" simulate --no-startup --axes 2 --duration 2 --seed 7 --capture-loss 0 \
  -o "$WORK/b.pcap" 2>/dev/null
cmp -s "$WORK/a.pcap" "$WORK/b.pcap" || fail "--capture-loss 0 changed the capture"

# A pcapng with interface statistics blocks: one after the 500th block (isb_ifdrop 5, isb_osdrop
# 1), the last one after the records (12 and 3), which counts.
"$NCSERVO" simulate --no-startup --axes 2 --duration 1 -o "$WORK/plain.pcapng" 2>/dev/null
python3 - "$WORK/plain.pcapng" "$WORK/drops.pcapng" <<'PY' || fail "cannot write the ISB"
import struct, sys
data = open(sys.argv[1], "rb").read()
assert struct.unpack_from("<I", data, 8)[0] == 0x1A2B3C4D, "little-endian pcapng expected"
def isb(ifdrop, osdrop):
    options = struct.pack("<HHQ", 5, 8, ifdrop) + struct.pack("<HHQ", 7, 8, osdrop) + struct.pack("<HH", 0, 0)
    body = struct.pack("<III", 0, 0, 0) + options
    length = 12 + len(body)
    return struct.pack("<II", 5, length) + body + struct.pack("<I", length)
at = 0
for _ in range(500):
    at += struct.unpack_from("<I", data, at + 4)[0]
open(sys.argv[2], "wb").write(data[:at] + isb(5, 1) + data[at:] + isb(12, 3))
PY
"$NCSERVO" validate "$WORK/drops.pcapng" >"$WORK/drops.txt" 2>&1
grep -q "^capture verdict: .*; the capture dropped 15 frames)" "$WORK/drops.txt" ||
  fail "no drops in the verdict line: $(cat "$WORK/drops.txt")"
grep -q "^capture drops: 15 frames (interface 12, system 3)" "$WORK/drops.txt" ||
  fail "no drops line: $(cat "$WORK/drops.txt")"
"$NCSERVO" validate --format json --fail-on never "$WORK/drops.pcapng" >"$WORK/drops.json"
python3 - "$WORK/drops.json" <<'PY' || fail "drops JSON: $(head -c 600 "$WORK/drops.json")"
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]
assert c["capture_dropped"] == {"frames": 15, "interface": 12, "system": 3}, c.get("capture_dropped")
PY
# The same counts from the same pcapng compressed, and piped in.
gzip -c "$WORK/drops.pcapng" >"$WORK/drops.pcapng.gz"
zstd -q -c "$WORK/drops.pcapng" >"$WORK/drops.pcapng.zst"
for kind in gz zst pipe; do
  if [ $kind = pipe ]; then
    "$NCSERVO" validate - <"$WORK/drops.pcapng" >"$WORK/drops-$kind.txt" 2>&1 || true
  else
    "$NCSERVO" validate "$WORK/drops.pcapng.$kind" >"$WORK/drops-$kind.txt" 2>&1 || true
  fi
  grep -q "^capture drops: 15 frames (interface 12, system 3)" "$WORK/drops-$kind.txt" ||
    fail "$kind: no drops line: $(tail -3 "$WORK/drops-$kind.txt")"
done
"$NCSERVO" validate --format json --fail-on never "$WORK/plain.pcapng" >"$WORK/plain.json"
python3 -c 'import json,sys; assert "capture_dropped" not in json.load(open(sys.argv[1]))["captures"][0]' \
  "$WORK/plain.json" || fail "capture_dropped without a statistics block"
echo "capture_loss: master copies missing from the capture counted, not lost cycles; pcapng drop counts in the verdict line and JSON"
