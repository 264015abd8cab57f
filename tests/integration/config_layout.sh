#!/usr/bin/env bash
# config_layout.sh SRC BUILD
# The explicit layout of a configuration file (docs/protocol.md §9.1) decodes a capture with the
# default layout switched off, in the CLI and in the plugin (preference ncservo.config).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
axes=3
python3 "$GEN" --axes $axes --cycles 300 -o "$WORK/capture" --truth "$WORK/truth.jsonl"
{
  echo "default_layout = false"
  for k in $(seq 0 $((axes - 1))); do
    printf '[[axis]]\nname = "axis%d"\noutputs = 0x%08X\ninputs = 0x%08X\n' \
      "$k" $((0x10000 + 10 * k)) $((0x10000 + 10 * axes + 40 * k))
  done
} >"$WORK/layout.toml"
chmod a+r "$WORK"/*
"$NCSERVO" decode --config "$WORK/layout.toml" "$WORK/capture" >"$WORK/decode.csv"
python3 "$CHECK" --format ncservo-csv "$WORK/truth.jsonl" "$WORK/decode.csv"
tshark_fields "$WORK/capture" "$WORK/tshark.tsv" -o "ncservo.config:$WORK/layout.toml"
python3 "$CHECK" --fields "$(fields_csv)" "$WORK/truth.jsonl" "$WORK/tshark.tsv"

# The same capture with the default layout switched off and no configuration: nothing decoded.
"$TSHARK" "$PLUGIN" -r "$WORK/capture" -o ncservo.default_layout:FALSE -Y ncservo.axis \
  >"$WORK/none.txt"
[ ! -s "$WORK/none.txt" ] || fail "default_layout FALSE still decoded frames"
rc=0
"$NCSERVO" decode --no-default-layout "$WORK/capture" >"$WORK/none.csv" 2>"$WORK/none.err" || rc=$?
[ $rc = 4 ] || fail "--no-default-layout: exit $rc, expected 4 (no servo decoded)"
[ "$(wc -l <"$WORK/none.csv")" = 1 ] || fail "--no-default-layout still decoded rows"
grep -q "no servo of this protocol found" "$WORK/none.err" || fail "no plain 'no servo' message"
echo "config_layout: explicit layout decodes; default layout can be switched off"
