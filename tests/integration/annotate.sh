#!/usr/bin/env bash
# annotate.sh SRC BUILD: `ncservo annotate` on the bundled, simulated and real
# captures. Stock tshark, without the plugin, shows exactly one comment per finding on its frame,
# each starting with the rule ID; the frames, their timestamps and lengths are the input's; a
# pcapng's existing comments and other blocks are kept (an earlier annotation's own comments are
# replaced, not doubled); --snippets keeps only frames near a
# finding; standard input and writing over the input are refused.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

"$NCSERVO" simulate --scenario commissioning --axes 3 --fault SE-003@1.2:1 -o "$WORK/sim.pcapng" 2>/dev/null
"$NCSERVO" simulate --scenario faults --probe esl -o "$WORK/sim-esl.pcap.zst" 2>/dev/null
inputs=("$SRC/captures/faults-4axis.pcap" "$SRC/captures/commissioning-4axis.pcap"
        "$SRC/captures/sim-faults-4axis.pcap" "$SRC/captures/sim-io-interleaved.pcapng"
        "$WORK/sim.pcapng" "$WORK/sim-esl.pcap.zst")

# frames CAPTURE OUT: number, epoch time, lengths and interface (a pcap's is 0) of every frame;
# comments CAPTURE OUT: the frames with comments as tshark's JSON. Stock tshark, no plugin.
frames() {
  "$TSHARK" none -r "$1" -T fields -e frame.number -e frame.time_epoch -e frame.len \
    -e frame.cap_len -e frame.interface_id 2>/dev/null |
    awk -F'\t' 'BEGIN { OFS = "\t" } { if ($5 == "") $5 = 0; print }' >"$2" || fail "tshark on $1"
}
comments() {
  "$TSHARK" none -r "$1" -T json -e frame.number -e frame.comment -Y frame.comment \
    >"$2" 2>/dev/null || fail "tshark comments of $1"
}

# check_comments COMMENTS.json FINDINGS.jsonl [OTHERS]: each finding's and incident's frame has its comment,
# once (a capture annotated again has its comments replaced), and no frame has another but
# frame 1's OTHERS (someone else's comment, kept).
check_comments() {
  python3 - "$@" <<'PY'
import collections, json, sys
others = sys.argv[3] if len(sys.argv) > 3 else None
shown = collections.defaultdict(list)
for packet in json.load(open(sys.argv[1])):
    layers = packet["_source"]["layers"]
    shown[int(layers["frame.number"][0])] += layers["frame.comment"]
if others is not None:
    assert others in shown[1], f"someone else's comment on frame 1 is gone: {shown[1]}"
    shown[1].remove(others)
    if not shown[1]:
        del shown[1]
expected = collections.defaultdict(list)
for line in open(sys.argv[2]):
    f = json.loads(line)
    if "rule" in f:
        expected[f["frame"]].append(f["rule"])
    if "incident" in f:  # docs/field.md: an incident's comment starts with INC-<cause>
        expected[f["incident"]["frame"]].append("INC-" + f["incident"]["cause"]["id"])
assert set(shown) == set(expected), f"frames with comments {sorted(shown)[:9]} != findings' and incidents' {sorted(expected)[:9]}"
for frame, rules in expected.items():
    got = sorted(c.split(" ")[0] for c in shown[frame])
    assert got == sorted(rules), f"frame {frame}: comments {shown[frame]} for findings {rules}"
print(sum(len(v) for v in expected.values()), "findings and incidents,", len(expected), "frames")
PY
}

# annotated INPUT: one comment per finding, the frames kept, and comments kept when annotated again.
annotated() {
  local input=$1 name
  name=$(basename "$input")
  local checked=0 rc=0  # 4 where no servo was decoded: annotate exits as validate does
  "$NCSERVO" validate --format jsonl --fail-on never "$input" >"$WORK/findings.jsonl" 2>/dev/null ||
    checked=$?
  [ $checked = 0 ] || [ $checked = 4 ] || fail "$name: validate exit $checked"
  "$NCSERVO" annotate "$input" "$WORK/out.pcapng" 2>"$WORK/err" || rc=$?
  [ $rc = $checked ] || fail "$name: exit $rc, validate's $checked: $(cat "$WORK/err")"
  comments "$WORK/out.pcapng" "$WORK/comments.json"
  check_comments "$WORK/comments.json" "$WORK/findings.jsonl" || fail "$name: comments"
  frames "$input" "$WORK/in.frames"
  frames "$WORK/out.pcapng" "$WORK/out.frames"
  cmp -s "$WORK/in.frames" "$WORK/out.frames" || fail "$name: frames differ: $(diff "$WORK/in.frames" "$WORK/out.frames" | head -4)"
  # Annotated again, with a colleague's comment on frame 1: ours replaced, theirs kept.
  editcap -a "1:checked by a colleague" "$WORK/out.pcapng" "$WORK/noted.pcapng" ||
    fail "$name: editcap -a"
  rc=0
  "$NCSERVO" annotate "$WORK/noted.pcapng" "$WORK/twice.pcapng" 2>/dev/null || rc=$?
  [ $rc = $checked ] || fail "$name: twice: exit $rc"
  comments "$WORK/twice.pcapng" "$WORK/twice.json"
  check_comments "$WORK/twice.json" "$WORK/findings.jsonl" "checked by a colleague" ||
    fail "$name: annotated again: ours not replaced, or the colleague's not kept"
  echo "ok $name"
}

for input in "${inputs[@]}"; do
  annotated "$input"
done

# --snippets: only frames within S seconds of a finding or an incident, their frames among them.
"$NCSERVO" annotate --snippets 0.05 "$SRC/captures/faults-4axis.pcap" "$WORK/snip.pcapng" 2>/dev/null ||
  fail "snippets: exit $?"
"$NCSERVO" validate --format jsonl --fail-on never "$SRC/captures/faults-4axis.pcap" >"$WORK/f.jsonl"
"$TSHARK" none -r "$WORK/snip.pcapng" -T fields -e frame.time_relative -e frame.comment \
  >"$WORK/snip.txt" 2>/dev/null
"$TSHARK" none -r "$SRC/captures/faults-4axis.pcap" -T fields -e frame.time_epoch >"$WORK/all.txt" 2>/dev/null
python3 - "$WORK/f.jsonl" "$WORK/snip.pcapng" "$WORK/all.txt" "$WORK/snip.txt" <<'PY' || fail "snippets"
import json, sys, subprocess
lines = [json.loads(l) for l in open(sys.argv[1])]
# Findings and incidents, each a frame and a time: the snippets are cut around both.
findings = [f for f in lines if "rule" in f] + [l["incident"] for l in lines if "incident" in l]
epochs = [float(l) for l in open(sys.argv[3])]
first = epochs[0]
near = [t for t in epochs if any(abs(t - first - f["time"]) <= 0.05 + 1e-6 for f in findings)]
kept = open(sys.argv[4]).read().splitlines()
assert len(kept) == len(near), f"{len(kept)} frames kept, {len(near)} within 0.05 s of a finding"
assert sum(1 for l in kept if "\t" in l and l.split("\t")[1]) == len({f["frame"] for f in findings})
PY
echo "ok --snippets"

# Refused: standard input (two passes), and the input as output.
rc=0; "$NCSERVO" annotate - "$WORK/x.pcapng" <"$SRC/captures/faults-4axis.pcap" 2>"$WORK/err" || rc=$?
[ "$rc" = 2 ] && grep -q "read twice" "$WORK/err" || fail "stdin: exit $rc: $(cat "$WORK/err")"
cp "$SRC/captures/faults-4axis.pcap" "$WORK/same.pcap"
rc=0; "$NCSERVO" annotate "$WORK/same.pcap" "$WORK/./same.pcap" 2>"$WORK/err" || rc=$?
[ "$rc" = 2 ] && grep -q "refusing to write over an input" "$WORK/err" || fail "input as output: exit $rc"
cmp -s "$WORK/same.pcap" "$SRC/captures/faults-4axis.pcap" || fail "the input was written"

# The real captures last: without them the cases above have run, and the test says it skipped these.
require_path "$REAL_CAPTURES" "real captures" "the bundled and simulated ones passed"
for input in "$REAL_CAPTURES"/*.pcapng "$REAL_CAPTURES"/*.cap; do
  annotated "$input"
done
# A pcapng's other blocks are copied as stored: its interfaces and their options.
multi="$REAL_CAPTURES/twincat-cyclic-multi-idb.pcapng"
"$NCSERVO" annotate "$multi" "$WORK/multi.pcapng" 2>"$WORK/err" || [ $? = 4 ] ||
  fail "multi-idb: $(cat "$WORK/err")"
interfaces() {  # interfaces CAPTURE OUT: capinfos' interface blocks, without the file name line
  capinfos -I "$1" >"$WORK/capinfos.out" 2>"$WORK/capinfos.err" ||
    fail "capinfos -I $1 exited $?: $(cat "$WORK/capinfos.err")"
  tail -n +2 "$WORK/capinfos.out" >"$2"
  [ -s "$2" ] || fail "capinfos -I $1 showed no interface"
}
interfaces "$multi" "$WORK/in.idb"
interfaces "$WORK/multi.pcapng" "$WORK/out.idb"
cmp -s "$WORK/in.idb" "$WORK/out.idb" || fail "multi-idb: interfaces differ: $(diff "$WORK/in.idb" "$WORK/out.idb" | head -6)"
echo "ok multi-idb: interfaces kept"
echo PASS
