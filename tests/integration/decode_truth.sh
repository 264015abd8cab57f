#!/usr/bin/env bash
# decode_truth.sh SRC BUILD GENERATOR-OPTIONS...
# Generates a capture with known truth (an independent generator, docs/protocol.md §9.4) and checks
# that tshark with the plugin and `ncservo decode` both give the exact value of every axis in
# every frame, TxPDO fields only in returned copies.
SRC=$1 BUILD=$2
shift 2
source "$SRC/tests/integration/lib.sh"
python3 "$GEN" "$@" -o "$WORK/capture" --truth "$WORK/truth.jsonl"
chmod a+r "$WORK"/*
tshark_fields "$WORK/capture" "$WORK/tshark.tsv"
python3 "$CHECK" --fields "$(fields_csv)" "$WORK/truth.jsonl" "$WORK/tshark.tsv"
"$NCSERVO" decode "$WORK/capture" >"$WORK/decode.csv" || fail "ncservo decode exited $?"
python3 "$CHECK" --format ncservo-csv "$WORK/truth.jsonl" "$WORK/decode.csv"
echo "decode_truth $*: tshark and ncservo decode match the truth"
