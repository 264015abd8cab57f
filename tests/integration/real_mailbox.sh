#!/usr/bin/env bash
# real_mailbox.sh SRC BUILD
# The CoE traffic of the real captures (the SOEM and Beckhoff start-ups read and write the PDO
# assignment over SDO) is decoded as stock Wireshark decodes it: every SDO answer `validate`
# lists in `drive_messages` is on a frame where stock tshark's `ecat_mailbox.coe.sdoidx` and
# `.sdosub` give the same index and subindex (stock leaves a download response without data
# undecoded: then only its request frame is compared), and its request frame holds the same
# object. And on no real capture an emergency, a link fault, a counter rise or a mailbox note:
# none of them holds a fault.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_path "$REAL_CAPTURES" "real captures"
require_program tshark
checked=0
for capture in "$REAL_CAPTURES"/*.pcap "$REAL_CAPTURES"/*.pcapng "$REAL_CAPTURES"/*.cap; do
  [ -f "$capture" ] || continue
  name=$(basename "$capture")
  "$NCSERVO" validate --format json --fail-on never --allow-empty "$capture" >"$WORK/report.json" ||
    fail "$name: validate exited $?"
  # Stock tshark's SDO fields, by frame (no plugin: the stock dissectors alone).
  tshark -r "$capture" -Y 'ecat_mailbox.coe.sdoidx' -T fields -E separator=' ' -e frame.number \
    -e ecat_mailbox.coe.sdoidx -e ecat_mailbox.coe.sdosub >"$WORK/stock.txt" 2>/dev/null ||
    fail "$name: stock tshark exited $?"
  python3 - "$WORK/report.json" "$WORK/stock.txt" "$name" <<'PY' || fail "$name: see above"
import json, sys
report = json.load(open(sys.argv[1]))["captures"][0]
name = sys.argv[3]
stock = {}
for line in open(sys.argv[2]):
    parts = line.split()
    if len(parts) < 3:
        continue
    # A frame may hold several datagrams: every (index, subindex) it shows.
    idx = [int(x, 16) for x in parts[1].split(",")]
    sub = [int(x, 16) for x in parts[2].split(",")]
    stock[int(parts[0])] = set(zip(idx, sub))
bad = []
for key in ("link_faults", "esc_errors", "mailbox_notes"):
    if report.get(key):
        bad.append(f"{key}: {report[key][:2]}")
listed = set()
short = 0
for m in report["drive_messages"]:
    if m["kind"] == "emergency":
        bad.append(f"an emergency on a capture without faults: {m}")
        continue
    want = (m["index"], m["subindex"])
    for key in ("frame", "request_frame"):
        if key not in m:
            bad.append(f"{m}: no {key}")
        elif m[key] not in stock and key == "frame" and m["kind"] == "sdo-download":
            # A download response of 4 bytes after the CoE header (no data, as the Beckhoff
            # start-up sends it): stock marks it "invalid length" and shows no index; the request
            # frame, which stock decodes, must still agree.
            short += 1
        elif want not in stock.get(m[key], set()):
            bad.append(f"{key} {m[key]}: ncservo 0x{want[0]:04X}:{want[1]}, stock {stock.get(m[key])}")
    listed.add(m["frame"])
print(f"{name}: {len(report['drive_messages'])} SDO answers as stock tshark decodes them "
      f"({short} short download responses stock leaves undecoded)")
if bad:
    print("\n".join(bad[:10]))
    sys.exit(1)
PY
  checked=$((checked + 1))
done
[ "$checked" -gt 0 ] || fail "no real capture found in $REAL_CAPTURES"
echo "real_mailbox: $checked captures"
