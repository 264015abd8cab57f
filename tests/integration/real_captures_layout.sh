#!/usr/bin/env bash
# real_captures_layout.sh SRC BUILD
# On the real captures with a start-up, the SM and FMMU layout the library learns for each slave
# (`ncservo decode --layout`) is what tshark's stock EtherCAT dissector shows for the start-up's
# 0x0800/0x0600 writes (tests/tools/stock_layout.py); none of their slaves is taken for a servo;
# and the legal start-ups raise no ESM finding but ESM-004 (information), while the one where
# the drive refuses SAFE-OP (AL status code 0x001D) raises exactly that ESM-003.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_path "$REAL_CAPTURES" "real captures"
real=$REAL_CAPTURES
# capture | ESM rules (warning or above) its start-up must raise
cases=(
  "wiki-beckhoff-startup.cap|"
  "ethercrab-dc-to-op.pcapng|"
  "ethercrab-outputs-to-op.pcapng|"
  "soem-akd-servo-pdo-mapping.pcapng|ESM-003"
)
for row in "${cases[@]}"; do
  IFS='|' read -r name want <<<"$row"
  capture="$real/$name"
  [ -f "$capture" ] || fail "no $capture"
  tshark -r "$capture" -T json --no-duplicate-keys -Y "ecat.fmmu || ecat.syncman" \
    >"$WORK/stock.json" 2>/dev/null || fail "$name: tshark exit $?"
  python3 "$SRC/tests/tools/stock_layout.py" "$WORK/stock.json" >"$WORK/stock.txt"
  [ -s "$WORK/stock.txt" ] || fail "$name: the stock dissector shows no SM/FMMU write"
  rc=0
  "$NCSERVO" decode --layout "$capture" >"$WORK/layout.txt" 2>"$WORK/err.txt" || rc=$?
  [ $rc = 4 ] || fail "$name: decode exit $rc, expected 4 (no servo)"
  grep -q "^# layout source: none, 0 axes" "$WORK/layout.txt" || fail "$name: $(head -1 "$WORK/layout.txt")"
  # our slave lines, without ring position, SM control bytes and "(off)" of disabled SMs, and
  # without the slaves the start-up configured nothing on
  grep '^# slave' "$WORK/layout.txt" | sed -e 's/^# slave [0-9]* //' -e 's/ control 0x[0-9A-F]*//g' \
    -e 's/; CoE PDOs .* bits in//' \
    -e 's/\(SM[0-9]* 0x[0-9A-F]*+[0-9]*\) (off)/\1/g' | grep ';' >"$WORK/learned.txt" || true
  diff -u "$WORK/stock.txt" "$WORK/learned.txt" >"$WORK/diff.txt" ||
    fail "$name: learned layout differs from the stock dissector's: $(cat "$WORK/diff.txt")"
  # The CoE PDO assignment the start-up wrote or read back sizes the process data as its SMs do.
  { grep '^# slave.*CoE PDOs' "$WORK/layout.txt" || true; } | python3 -c '
import re, sys
for line in sys.stdin:
    sm = {int(n): int(l) for n, l in re.findall(r"SM(\d) 0x[0-9A-F]+\+(\d+)", line)}
    out, inp = re.search(r"CoE PDOs (\S+) bits out, (\S+) bits in", line).groups()
    for bits, n in ((out, 2), (inp, 3)):
        if bits != "?":
            assert int(bits) == 8 * sm.get(n, 0), f"CoE {bits} bits, SM{n} {sm.get(n)} bytes: {line}"
' || fail "$name: the CoE PDO sizes disagree with the sync managers"
  "$NCSERVO" validate --format json --fail-on never --allow-empty "$capture" >"$WORK/report.json"
  python3 - "$WORK/report.json" "$want" <<'PY' || fail "$name: ESM findings differ"
import json, sys
findings = json.load(open(sys.argv[1]))["captures"][0]["findings"]
serious = sorted({f["rule"] for f in findings if f["severity"] != "info" and f["rule"].startswith("ESM-")})
want = sorted(sys.argv[2].split()) if sys.argv[2] else []
assert serious == want, f"findings at warning or above: {serious}, expected {want}"
# the only information finding a start-up may raise is ESM-004
other = sorted({f["rule"] for f in findings if f["severity"] == "info" and f["rule"].startswith("ESM-")} - {"ESM-004"})
assert not other, f"information findings other than ESM-004: {other}"
PY
  echo "ok $name: $(wc -l <"$WORK/learned.txt") slaves' SMs and FMMUs as the stock dissector shows them; $(grep -c 'CoE PDOs' "$WORK/layout.txt") with CoE PDO sizes"
done
# The AKD's assignment and mapping, read back over CoE, give the 17 + 17 bytes of its SMs.
{ "$NCSERVO" decode --layout "$real/soem-akd-servo-pdo-mapping.pcapng" 2>/dev/null || true; } |
  grep -q "SM2 0x1100+17 .*CoE PDOs 136 bits out, 136 bits in" || fail "the AKD's CoE PDO mapping was not learned"
echo "ok: the AKD's CoE PDO assignment and mapping give its 17 + 17 bytes"
