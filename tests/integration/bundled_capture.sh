#!/usr/bin/env bash
# bundled_capture.sh SRC BUILD
# Each bundled capture is exactly what its documented command regenerates; `ncservo validate` on
# it gives its golden report; and on the faults capture it reports exactly what was injected.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
for name in commissioning-4axis faults-4axis; do
  cmd=$(grep -o "python3 tests/tools/gen_capture.py [^\`]*-o captures/$name.pcap" "$SRC/captures/README.md")
  [ -n "$cmd" ] || fail "no regeneration command for $name in captures/README.md"
  cmd=${cmd//captures\//$WORK/}
  (cd "$SRC" && eval "$cmd")
  cmp "$SRC/captures/$name.pcap" "$WORK/$name.pcap" || fail "$name.pcap differs from its regeneration"
  if [ -f "$SRC/captures/$name.findings.json" ]; then
    cmp "$SRC/captures/$name.findings.json" "$WORK/$name.findings.json" ||
      fail "$name.findings.json differs from its regeneration"
  fi

  "$NCSERVO" validate --format json --fail-on never "$SRC/captures/$name.pcap" >"$WORK/$name.json" ||
    fail "$name: validate exit $?"
  python3 "$SRC/tests/tools/golden.py" <"$WORK/$name.json" >"$WORK/$name.golden.json"
  diff -u "$SRC/captures/$name.expected.json" "$WORK/$name.golden.json" >"$WORK/diff.txt" ||
    fail "$name: report differs from captures/$name.expected.json: $(head -40 "$WORK/diff.txt")"
  if [ -f "$SRC/captures/$name.findings.json" ]; then
    python3 "$SRC/tests/tools/check_findings.py" "$WORK/$name.json" "$SRC/captures/$name.findings.json" ||
      fail "$name: findings differ from the injections"
  fi
done
# The clean session has no finding at all, and passes.
"$NCSERVO" validate "$SRC/captures/commissioning-4axis.pcap" >"$WORK/clean.txt" || fail "clean capture fails"
grep -q "^verdict: PASS - 0 errors, 0 warnings, 0 info" "$WORK/clean.txt" || fail "$(tail -1 "$WORK/clean.txt")"
rows=$("$NCSERVO" decode "$SRC/captures/commissioning-4axis.pcap" | tail -n +2 | wc -l)
[ "$rows" = 8000 ] || fail "commissioning capture decodes to $rows rows, expected 8000 (4 axes, 2000 cycles)"
echo "bundled_capture: identical to their regeneration, golden reports, injected findings"
