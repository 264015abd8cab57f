#!/usr/bin/env bash
# capture_kinds.sh SRC BUILD
# The same simulated session as it may come (docs/protocol.md §8): behind ESL probe headers (before
# and after the frame, capture timestamps with a PC's noise), as Linux cooked captures v1 and v2,
# gzip- and zstd-compressed (from a file and from standard input). Each gives the findings, axes
# and decoded rows of the plain capture; ESL captures are timed by the probe (auto), or by the PC
# with --timestamps capture; frames without a probe timestamp and CRC errors are reported; the
# plugin shows the same fields with and without Wireshark's esl_eth heuristic.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
WRAP="$SRC/tests/tools/wrap_capture.py"
plain="$WORK/plain.pcap"
"$NCSERVO" simulate --scenario faults --seed 5 -o "$plain" 2>/dev/null
chmod a+r "$plain"
"$NCSERVO" validate --format json --fail-on never "$plain" >"$WORK/plain.json"
"$NCSERVO" decode "$plain" >"$WORK/plain.csv"

# same_report JSON TIMESTAMPS: findings, axes and layout as the plain capture's
same_report() {
  python3 - "$WORK/plain.json" "$1" "$2" <<'PY' || fail "$1: report differs from the plain capture's"
import json, sys
a = json.load(open(sys.argv[1]))["captures"][0]
b = json.load(open(sys.argv[2]))["captures"][0]
assert a["findings"], "the plain capture has findings to compare"
def relative(value):  # time_utc is each capture's own clock: the wrapped one's PC stamps differ
    if isinstance(value, dict):
        return {k: relative(v) for k, v in value.items() if k != "time_utc"}
    return [relative(v) for v in value] if isinstance(value, list) else value
for key in ("findings", "axes", "layout", "summary", "frames", "cycles", "verdict"):
    assert relative(a[key]) == relative(b[key]), (key, a[key], b[key])
assert b["timing"]["timestamps"] == sys.argv[3], b["timing"]
PY
}

for place in before after; do
  wrapped="$WORK/esl-$place.pcap"
  python3 "$WRAP" "$plain" "$wrapped" --esl "$place" --port 3
  chmod a+r "$wrapped"
  "$NCSERVO" validate --format json --fail-on never "$wrapped" >"$WORK/esl.json"
  same_report "$WORK/esl.json" probe
  "$NCSERVO" decode "$wrapped" >"$WORK/esl.csv" 2>"$WORK/esl.err"
  cmp -s "$WORK/plain.csv" "$WORK/esl.csv" || fail "ESL $place: decode rows differ"
  grep -q "timestamps: probe" "$WORK/esl.err" || fail "ESL $place: decode does not say probe"
  "$NCSERVO" validate --fail-on never "$wrapped" >"$WORK/esl.txt"
  grep -qx "timestamps: probe" "$WORK/esl.txt" || fail "ESL $place: no text line"
  # the PC's clock: the same frames, other times
  "$NCSERVO" validate --format json --fail-on never --timestamps capture "$wrapped" >"$WORK/pc.json"
  python3 - "$WORK/plain.json" "$WORK/pc.json" <<'PY' || fail "ESL $place: --timestamps capture"
import json, sys
a = json.load(open(sys.argv[1]))["captures"][0]
b = json.load(open(sys.argv[2]))["captures"][0]
assert b["timing"]["timestamps"] == "capture", b["timing"]
assert "unused (--timestamps capture)" in b["probe"]["note"], b["probe"]
assert [f["time"] for f in a["findings"]] != [f["time"] for f in b["findings"]]
PY
  # the plugin decodes behind the header whether or not the esl_eth heuristic is on
  tshark_fields "$plain" "$WORK/plain.tsv"
  tshark_fields "$wrapped" "$WORK/esl.tsv"
  cmp -s "$WORK/plain.tsv" "$WORK/esl.tsv" || fail "ESL $place: plugin fields differ"
  tshark_fields "$wrapped" "$WORK/esl-heur.tsv" --enable-heuristic esl_eth
  cmp -s "$WORK/plain.tsv" "$WORK/esl-heur.tsv" || fail "ESL $place: plugin fields differ (esl_eth)"
  echo "ok ESL $place"
done

# A frame without a probe timestamp, and one the probe saw with a CRC error.
python3 "$WRAP" "$plain" "$WORK/gaps.pcap" --esl before --unstamped 300,301 --crc-error 500
"$NCSERVO" validate --format json --fail-on never "$WORK/gaps.pcap" >"$WORK/gaps.json"
python3 - "$WORK/gaps.json" <<'PY' || fail "unstamped and CRC-error frames"
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]
p = c["probe"]
assert c["timing"]["timestamps"] == "probe", c["timing"]
assert (p["unstamped"], p["first_unstamped_frame"]) == (2, 300), p
assert (p["crc_errors"], p["first_crc_error_frame"]) == (1, 500), p
assert "frame 300" in p["note"] and "CRC error" in p["note"], p["note"]
assert all(f["frame"] != 500 for f in c["findings"])
PY
"$NCSERVO" validate --fail-on never "$WORK/gaps.pcap" >"$WORK/gaps.txt"
grep -q "^probe: 2 EtherCAT frames without a probe timestamp (first: frame 300)" "$WORK/gaps.txt" ||
  fail "text report: no probe line"
echo "ok unstamped and CRC-error frames"

for link in sll sll2; do
  python3 "$WRAP" "$plain" "$WORK/$link.pcap" --link "$link"
  "$NCSERVO" validate --format json --fail-on never "$WORK/$link.pcap" >"$WORK/$link.json"
  same_report "$WORK/$link.json" capture
  echo "ok Linux cooked $link"
done

gzip -c "$plain" >"$WORK/capture.gz"
zstd -q -c "$plain" >"$WORK/capture.zst"
for compressed in "$WORK/capture.gz" "$WORK/capture.zst"; do
  "$NCSERVO" validate --format json --fail-on never "$compressed" >"$WORK/c.json"
  same_report "$WORK/c.json" capture
  "$NCSERVO" validate --format json --fail-on never - <"$compressed" >"$WORK/c.json"
  same_report "$WORK/c.json" capture
  cat "$compressed" | "$NCSERVO" validate --format json --fail-on never - >"$WORK/c.json"
  same_report "$WORK/c.json" capture
  cat "$compressed" | "$NCSERVO" decode - >"$WORK/c.csv"
  cmp -s "$WORK/plain.csv" "$WORK/c.csv" || fail "$compressed: decode rows differ"
  # cut in the middle: exit 3, the file and the damage named, the frames before reported
  head -c $(($(stat -c %s "$compressed") / 2)) "$compressed" >"$WORK/cut"
  set +e
  "$NCSERVO" validate --format json "$WORK/cut" >"$WORK/cut.json" 2>"$WORK/cut.err"
  rc=$?
  set -e
  [ $rc = 3 ] || fail "cut $compressed: exit $rc, expected 3"
  grep -q "$WORK/cut: frame [0-9]*: the \(gzip\|zstd\) stream is cut short" "$WORK/cut.err" ||
    fail "cut $compressed: $(cat "$WORK/cut.err")"
  python3 -c "import json,sys; c=json.load(open(sys.argv[1]))['captures'][0]; assert c['frames'] > 1000, c['frames']" \
    "$WORK/cut.json" || fail "cut $compressed: frames before the damage not reported"
  echo "ok $(basename "$compressed")"
done
