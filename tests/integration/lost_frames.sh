#!/usr/bin/env bash
# lost_frames.sh SRC BUILD: every frame range an incident names as lost (its text and evidence)
# and every master frame COM-004 names is a master copy that got no returned copy, as stock
# tshark shows the capture: a master copy (source MAC without the bit the first slave sets) whose
# datagram indices come back in no returned copy. The ranges are whole runs of such copies.
# Checked on the bundled incidents capture (a 12-cycle outage), the faults capture and the
# simulator's COM-005.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_program tshark
"$NCSERVO" simulate --fault COM-005@1.0 -o "$WORK/com005.pcap" 2>/dev/null
for capture in "$SRC/captures/sim-incidents-4axis.pcap" "$SRC/captures/sim-faults-4axis.pcap" \
  "$WORK/com005.pcap"; do
  name=$(basename "$capture")
  tshark -r "$capture" -T fields -e frame.number -e eth.src -e ecat.idx >"$WORK/$name.tsv" 2>/dev/null ||
    fail "$name: tshark"
  "$NCSERVO" validate --format json --fail-on never -o "$WORK/$name.json" "$capture" ||
    fail "$name: validate exit $?"
  python3 - "$WORK/$name.tsv" "$WORK/$name.json" <<'PY' || fail "$name: the frames named are not the lost ones"
import json, re, sys
# A master copy is answered by a returned copy of its indices before the next master copy (the
# 8-bit indices wrap, so only that window counts).
frames = []
for line in open(sys.argv[1]):
    number, src, indices = (line.rstrip("\n").split("\t") + ["", ""])[:3]
    if indices:
        frames.append((int(number), bool(int(src.split(":")[0], 16) & 0x02), indices))
order, unanswered = [], set()
for i, (number, is_returned, indices) in enumerate(frames):
    if is_returned:
        continue
    order.append(number)
    answered = False
    for later_number, later_returned, later_indices in frames[i + 1:]:
        if not later_returned:
            break
        answered = answered or later_indices == indices
    if not answered:
        unanswered.add(number)
def run_of(first, last):
    # first..last is a whole run of consecutive master copies none of which came back.
    i, j = order.index(first), order.index(last)
    inside = order[i:j + 1]
    assert all(n in unanswered for n in inside), (first, last, [n for n in inside if n not in unanswered])
    assert i == 0 or order[i - 1] not in unanswered, ("the run starts earlier", order[i - 1])
    assert j + 1 == len(order) or order[j + 1] not in unanswered, ("the run goes on", order[j + 1])
c = json.load(open(sys.argv[2]))["captures"][0]
named = 0
for incident in c["incidents"]:
    text = incident["cause"]["text"]
    for m in re.finditer(r"cycles? lost \(frames? (\d+)(?:-(\d+))?\)", text):
        first, last = int(m.group(1)), int(m.group(2) or m.group(1))
        run_of(first, last)
        lost = int(re.search(r"(\d+) cycles? lost \(frame", text).group(1))
        assert lost == order.index(last) - order.index(first) + 1, (text, first, last)
        named += 1
    for e in incident["evidence"]:
        if re.match(r"\d+ cycles? lost$", e["what"]):
            assert e["frame"] in unanswered, (e, incident["fingerprint"])
for f in c["findings"]:
    if f["rule"] == "COM-004":
        master = int(re.search(r"master frame (\d+)", f["message"]).group(1))
        assert master in unanswered, f
        named += 1
assert named > 0, "no lost frames named: nothing checked"
print(f"{named} ranges and frames named, {len(unanswered)} master copies unanswered")
PY
done
echo "lost_frames: every lost frame range names the master copies tshark shows unanswered"
