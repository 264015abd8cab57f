#!/usr/bin/env bash
# no_ethercat.sh SRC BUILD: a capture with no EtherCAT frame at all (a header-only pcap, a
# loopback capture, `monitor -i lo`) says so, not "no servo ... give the layout" (docs/cli.md);
# a reason is one line in every format, and the --config example is in the text report only.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
python3 - "$WORK" <<'PY'
import struct, sys
work = sys.argv[1]
header = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)
open(f"{work}/empty.pcap", "wb").write(header)
# What a Linux loopback capture holds: Ethernet frames of IPv4, zero addresses.
frame = bytes(12) + b"\x08\x00" + b"\x45" + bytes(39)
records = b"".join(struct.pack("<IIII", 1000 + i, 0, len(frame), len(frame)) + frame for i in range(5))
open(f"{work}/lo.pcap", "wb").write(header + records)
PY
# EtherCAT whose inference refuses: an idle servo behind two CiA 402 drives of the same PDO sizes.
python3 "$GEN" --axes 1 --cia402 2 --idle-all -o "$WORK/idle.pcap" >/dev/null

# validate_no_servo CAPTURE REASON: exit 4, the reason in text and JSON, one line.
validate_no_servo() {
  local capture=$1 reason=$2 rc=0
  "$NCSERVO" validate "$capture" >"$WORK/out" 2>"$WORK/err" || rc=$?
  [ "$rc" = 4 ] || fail "validate $capture: exit $rc, expected 4"
  grep -qxF "NO SERVO: $reason" "$WORK/out" || fail "$capture text: $(grep NO "$WORK/out")"
  rc=0
  "$NCSERVO" validate --format json "$capture" >"$WORK/out.json" 2>/dev/null || rc=$?
  [ "$rc" = 4 ] || fail "validate --format json $capture: exit $rc, expected 4"
  python3 - "$WORK/out.json" "$reason" <<'PY' || fail "$capture json reason"
import json, sys
reason = json.load(open(sys.argv[1]))["captures"][0]["reason"]
assert reason.startswith(sys.argv[2]) and "\n" not in reason and "[[axis]]\n" not in reason, repr(reason)
PY
}

validate_no_servo "$WORK/empty.pcap" "no EtherCAT frame in the capture: it holds no frame"
! grep -q 'axis\]\]\|--config' "$WORK/out" || fail "empty.pcap: a layout example where no layout helps"
validate_no_servo "$WORK/lo.pcap" "no EtherCAT frame in the capture: its 5 frames are other traffic"
! grep -q 'axis\]\]\|--config' "$WORK/out" || fail "lo.pcap: a layout example where no layout helps"
echo "ok an empty and a loopback capture: no EtherCAT frame"

# EtherCAT with an idle servo: the inference refuses, and the text (only) shows a --config example.
rc=0
"$NCSERVO" validate "$WORK/idle.pcap" >"$WORK/out" 2>/dev/null || rc=$?
[ "$rc" = 4 ] || fail "idle.pcap: exit $rc, expected 4"
grep -q '^NO SERVO: no servo of this protocol found in the cyclic traffic.*give the layout in a --config file' "$WORK/out" ||
  fail "idle.pcap text: $(grep NO "$WORK/out")"
grep -q '^    \[\[axis\]\]$' "$WORK/out" || fail "idle.pcap: no [[axis]] example in the text"
"$NCSERVO" validate --format json "$WORK/idle.pcap" >"$WORK/out.json" 2>/dev/null || true
python3 -c 'import json,sys; r=json.load(open(sys.argv[1]))["captures"][0]["reason"]; assert "\n" not in r and "[[axis]]\n" not in r, repr(r)' \
  "$WORK/out.json" || fail "idle.pcap: the json reason is not one line"
"$NCSERVO" validate --format jsonl "$WORK/idle.pcap" >"$WORK/out.jsonl" 2>/dev/null || true
python3 -c 'import json,sys; [json.loads(l) for l in open(sys.argv[1])]' "$WORK/out.jsonl" || fail "jsonl"
# The same with inference off.
rc=0
"$NCSERVO" validate --no-default-layout "$SRC/captures/commissioning-4axis.pcap" >"$WORK/out" 2>/dev/null || rc=$?
[ "$rc" = 4 ] || fail "--no-default-layout: exit $rc, expected 4"
grep -q '^    outputs = 0x' "$WORK/out" || fail "--no-default-layout: no example: $(cat "$WORK/out")"
echo "ok an idle servo, inference off: the example in the text, one line in json"

# Live on the loopback: root or the capture capability.
[ "$(id -u)" = 0 ] || skip "monitor -i lo needs root"
rc=0
timeout 20 "$NCSERVO" monitor -i lo --duration 1 >"$WORK/out" 2>"$WORK/err" || rc=$?
[ "$rc" = 4 ] || fail "monitor -i lo: exit $rc, expected 4: $(cat "$WORK/err")"
grep -q '^NO SERVO: no EtherCAT frame in the capture' "$WORK/out" || fail "monitor text: $(cat "$WORK/out")"
! grep -q 'axis\]\]' "$WORK/out" || fail "monitor -i lo: a layout example where no layout helps"
echo "no_ethercat: empty, loopback and monitor -i lo say no EtherCAT frame; reasons one line"
