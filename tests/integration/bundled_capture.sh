#!/usr/bin/env bash
# bundled_capture.sh SRC BUILD
# The bundled capture is exactly what its documented command regenerates, and it decodes.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
cmd=$(grep -o 'python3 tests/tools/gen_capture.py [^`]*-o captures/commissioning-4axis.pcap' "$SRC/captures/README.md")
[ -n "$cmd" ] || fail "no regeneration command in captures/README.md"
(cd "$SRC" && eval "${cmd/-o captures\/commissioning-4axis.pcap/-o $WORK/regenerated.pcap}")
cmp "$SRC/captures/commissioning-4axis.pcap" "$WORK/regenerated.pcap" || fail "bundled capture differs from its regeneration"
rows=$("$NCSERVO" decode "$SRC/captures/commissioning-4axis.pcap" | tail -n +2 | wc -l)
[ "$rows" -gt 0 ] || fail "bundled capture decodes to nothing"
echo "bundled_capture: identical to its regeneration, $rows rows"
