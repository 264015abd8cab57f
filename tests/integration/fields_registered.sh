#!/usr/bin/env bash
# fields_registered.sh SRC BUILD
# `tshark -G fields` with the plugin lists exactly the fields `ncservo fields` lists (and so
# docs/fields.md): the field table's, the derived ones, one expert item per rule and the expert
# notes (the registrations are generated from those tables); and the plugin loads next to the
# stock EtherCAT one.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
"$TSHARK" "$PLUGIN" -G fields >"$WORK/fields.txt" 2>"$WORK/err.txt" || fail "tshark -G fields exit $?"
[ ! -s "$WORK/err.txt" ] || fail "stderr: $(cat "$WORK/err.txt")"
awk -F'\t' '$1 == "F" && $3 ~ /^ncservo\./ {print $3}' "$WORK/fields.txt" | sort >"$WORK/registered.txt"
"$NCSERVO" fields | cut -f1 | sort >"$WORK/table.txt"
diff -u "$WORK/table.txt" "$WORK/registered.txt" || fail "registered fields differ from the table"
grep -q -P '^P\tNC-Servo EtherCAT process data\tncservo$' "$WORK/fields.txt" || fail "protocol not registered"
grep -q -P '^F\t[^\t]*\tecat\.cmd\t' "$WORK/fields.txt" || fail "stock EtherCAT plugin not loaded"
grep -q -P '^F\tSE\tncservo\.scw\.se\tFT_UINT32\tncservo\tBASE_DEC\t0x3\t' "$WORK/fields.txt" || fail "scw.se"
grep -q -P '^F\tServo control word\tncservo\.scw\tFT_UINT32\tncservo\tBASE_HEX\t0x0\t' "$WORK/fields.txt" || fail "scw"
grep -q -P '^F\t[^\t]*\tncservo\.malformed\tFT_NONE\t' "$WORK/fields.txt" || fail "expert ncservo.malformed"
grep -q -P '^F\tActual position\tncservo\.actpos\tFT_INT64\tncservo\tBASE_DEC' "$WORK/fields.txt" || fail "actpos"
grep -q -P '^F\tMessage data\tncservo\.msg_data\tFT_FLOAT\t' "$WORK/fields.txt" || fail "msg_data"
grep -q -P '^F\tFollowerErr \(E09\)\tncservo\.sew\.following\tFT_BOOLEAN\tncservo\t32\t0x80000\t' "$WORK/fields.txt" || fail "sew.following"
echo "fields_registered: $(wc -l <"$WORK/registered.txt") ncservo fields, as in the table"
