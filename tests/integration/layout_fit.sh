#!/usr/bin/env bash
# layout_fit.sh SRC BUILD
# A configured layout that does not fit says so (docs/layout.md#a-layout-that-does-not-fit): one
# axis's inputs two bytes off give exactly one warning, naming that axis, in the text and JSON
# reports and on standard error; the exact configuration gives none.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
"$NCSERVO" simulate -o "$WORK/c.pcap" --layout-config "$WORK/exact.toml" 2>/dev/null
python3 - "$WORK/exact.toml" "$WORK/off.toml" <<'PY'
import sys, tomllib
axes = tomllib.load(open(sys.argv[1], "rb"))["axis"]
with open(sys.argv[2], "w") as out:
    for i, a in enumerate(axes):
        inputs = a["inputs"] + (2 if i == 1 else 0)
        out.write(f'[[axis]]\nname = "{a["name"]}"\noutputs = {a["outputs"]:#x}\ninputs = {inputs:#x}\n')
PY

rc=0
"$NCSERVO" validate --config "$WORK/exact.toml" "$WORK/c.pcap" >"$WORK/out" 2>"$WORK/err" || rc=$?
[ "$rc" = 0 ] || fail "exact configuration: exit $rc"
! grep -q "does not fit" "$WORK/out" "$WORK/err" || fail "exact configuration: $(grep 'does not fit' "$WORK/out")"

"$NCSERVO" validate --config "$WORK/off.toml" "$WORK/c.pcap" >"$WORK/out" 2>"$WORK/err" || true
[ "$(grep -c '^warning: layout does not fit: ' "$WORK/out")" = 1 ] || fail "text: $(grep 'fit' "$WORK/out")"
grep -q "^warning: layout does not fit: axis1: the data at inputs 0x00010052 does not look like this protocol's TxPDO: .*message code -\?[0-9]* outside 0..9" "$WORK/out" ||
  fail "text warning: $(grep 'does not fit' "$WORK/out")"
[ "$(grep -c 'layout does not fit: axis1' "$WORK/err")" = 1 ] || fail "stderr: $(cat "$WORK/err")"
# The warning comes before the findings it explains.
first=$(grep -n -m1 -v '^== ' "$WORK/out" | cut -d: -f1)
[ "$(sed -n "${first}p" "$WORK/out" | cut -c1-28)" = "warning: layout does not fit" ] || fail "not first: $(head -3 "$WORK/out")"
"$NCSERVO" validate --format json --config "$WORK/off.toml" "$WORK/c.pcap" >"$WORK/out" 2>/dev/null || true
python3 - "$WORK/out" <<'PY' || fail "json"
import json, sys
w = json.load(open(sys.argv[1]))["captures"][0]["layout"]["warnings"]
assert len(w) == 1 and w[0].startswith("axis1: the data at inputs 0x00010052"), w
PY
echo "ok one warning for the axis off by two, none for the exact layout"
