#!/usr/bin/env bash
# pcapng_interfaces.sh SRC BUILD
# A pcapng of two interfaces (docs/cli.md#interfaces), made from the bundled faults capture by
# tests/tools/interfaces_capture.py, which numbers each original frame anew:
# - office: the bus on interface 0 (Ethernet) and a Linux cooked office port on interface 1 with
#   UDP and ARP between the bus's frames. `ncservo validate` gives the original's verdict and
#   findings (at the frames renumbered), from the file, gzip on standard input and zstd alike;
#   JSON `interfaces` and the text's `interfaces:` line say what each held; `tshark -2` with the
#   plugin shows the original's ncservo fields on the EtherCAT frames and none on the others.
# - tap: master copies on interface 0, returned copies on interface 1 (both Ethernet), some
#   written before their master copy: merged by time, the original's findings again.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_program gzip zstd
cap="$SRC/captures/faults-4axis.pcap"
for kind in office tap; do
  python3 "$SRC/tests/tools/interfaces_capture.py" $kind "$cap" "$WORK/$kind.pcapng" "$WORK/$kind.map"
done
chmod a+r "$WORK"/*
"$NCSERVO" validate --format json --fail-on never "$cap" >"$WORK/original.json" ||
  fail "validate exited $? on $cap"

# same_as_original KIND REPORT LINK_TYPE_1 ETHERCAT_1: the report of KIND's capture holds the
# original's verdict, counts and findings (frames through the map), and its interfaces.
same_as_original() {
  python3 - "$WORK/original.json" "$2" "$WORK/$1.map" "$3" "$4" <<'PY'
import json, sys
original, report, mapping = (json.load(open(p)) for p in sys.argv[1:4])
link_type, ethercat = int(sys.argv[4]), sys.argv[5] == "true"
o, r = original["captures"][0], report["captures"][0]
frames = mapping["frames"]
for key in ("verdict", "summary", "cycles"):
    if o[key] != r[key]:
        sys.exit(f"{key}: {r[key]}, the original's {o[key]}")
def finding(f, renumber):
    return (f["rule"], f["severity"], f["axis"], renumber(f["frame"]), renumber(f["since_frame"]),
            f["time"], f["fingerprint"])
want = [finding(f, lambda n: frames[n - 1]) for f in o["findings"]]
got = [finding(f, lambda n: n) for f in r["findings"]]
if not want:
    sys.exit("the original has no finding to compare")
if got != want:
    diff = [(w, g) for w, g in zip(want, got) if w != g][:3]
    sys.exit(f"findings differ ({len(got)} against {len(want)}): {diff}")
counts = mapping["interfaces"]
interfaces = [{"id": 0, "link_type": 1, "frames": counts[0], "ethercat": True},
              {"id": 1, "link_type": link_type, "frames": counts[1], "ethercat": ethercat}]
if r["interfaces"] != interfaces:
    sys.exit(f"interfaces: {r['interfaces']}, expected {interfaces}")
if r["frames"] != sum(counts) or o["interfaces"] != [
        {"id": 0, "link_type": 1, "frames": o["frames"], "ethercat": True}]:
    sys.exit(f"frames {r['frames']}, interfaces of the original {o['interfaces']}")
PY
}

# The office port beside the bus: from the file, and compressed through standard input.
"$NCSERVO" validate --format json --fail-on never "$WORK/office.pcapng" >"$WORK/office.json" ||
  fail "validate exited $? on the office capture"
same_as_original office "$WORK/office.json" 113 false || fail "office: not the original's report"
gzip -c "$WORK/office.pcapng" | "$NCSERVO" validate --format json --fail-on never - >"$WORK/stdin.json" ||
  fail "validate exited $? on the gzip office capture from standard input"
same_as_original office "$WORK/stdin.json" 113 false || fail "office, gzip from standard input"
zstd -q -c "$WORK/office.pcapng" >"$WORK/office.pcapng.zst"
"$NCSERVO" validate --format json --fail-on never "$WORK/office.pcapng.zst" >"$WORK/zstd.json" ||
  fail "validate exited $? on the zstd office capture"
same_as_original office "$WORK/zstd.json" 113 false || fail "office, zstd"
counts=$(python3 -c 'import json,sys; print(*json.load(open(sys.argv[1]))["interfaces"])' "$WORK/office.map")
read -r ethernet cooked <<<"$counts"
set +e
"$NCSERVO" validate "$WORK/office.pcapng" >"$WORK/office.txt"
rc=$?
"$NCSERVO" validate "$cap" >"$WORK/original.txt"
original_rc=$?
set -e
[ $rc = $original_rc ] || fail "office: exit $rc, the original's $original_rc"
line="interfaces: 2 (0: Ethernet, $ethernet frames, EtherCAT; 1: Linux cooked, $cooked frames)"
grep -qxF "$line" "$WORK/office.txt" || fail "no '$line' in: $(grep interfaces "$WORK/office.txt")"
! grep -q "^interfaces:" "$WORK/original.txt" || fail "an interfaces line for one interface"

# The plugin: every ncservo field of the original's frames on their new numbers, nothing on the
# office port's.
fields=(-e frame.number -e ncservo.axis_name -e ncservo.state -e ncservo.transition -e ncservo.edge
        -e ncservo.finding -e ncservo.since_frame)
for f in "${ALL_FIELDS[@]}"; do fields+=(-e "$f"); done
for capture in "$cap" "$WORK/office.pcapng"; do
  "$TSHARK" "$PLUGIN" -2 -r "$capture" -T fields -E occurrence=a -E aggregator='|' "${fields[@]}" \
    >"$WORK/$(basename "$capture").tsv" 2>"$WORK/tshark.err" || fail "tshark exited $? on $capture"
  [ ! -s "$WORK/tshark.err" ] || fail "tshark printed on stderr: $(head -3 "$WORK/tshark.err")"
done
python3 - "$WORK/$(basename "$cap").tsv" "$WORK/office.pcapng.tsv" "$WORK/office.map" <<'PY' ||
import json, re, sys
frames = json.load(open(sys.argv[3]))["frames"]
def rows(path):
    return [line.rstrip("\n").split("\t") for line in open(path)]
original, office = rows(sys.argv[1]), rows(sys.argv[2])
new_of = {str(i + 1): str(n) for i, n in enumerate(frames)}
by_number = {row[0]: row for row in office}
if len(office) != len(frames) + json.load(open(sys.argv[3]))["interfaces"][1]:
    sys.exit(f"{len(office)} frames in the office capture")
shown = 0
for row in original:
    # A finding's text names frames too ("the master frame 3501").
    finding = re.sub(r"(frames? )(\d+)", lambda m: m[1] + new_of[m[2]], row[5])
    since = "|".join(new_of[n] for n in row[6].split("|") if n)
    want = [new_of[row[0]], *row[1:5], finding, since, *row[7:]]
    got = by_number[want[0]]
    if got != want:
        sys.exit(f"frame {row[0]} (now {want[0]}): {got[1:7]} against {want[1:7]}")
    shown += any(row[1:])
mapped = set(new_of.values())
extra = [row for row in office if row[0] not in mapped and any(row[1:])]
if extra or shown < 5000:
    sys.exit(f"{len(extra)} office frames with ncservo fields; {shown} frames shown")
PY
  fail "tshark: the office capture's ncservo fields are not the original's"

# A TAP's two directions, some returned copies written before their master copies.
"$NCSERVO" validate --format json --fail-on never "$WORK/tap.pcapng" >"$WORK/tap.json" ||
  fail "validate exited $? on the tap capture"
same_as_original tap "$WORK/tap.json" 1 true || fail "tap: not the original's report"
python3 -c 'import json,sys; m=json.load(open(sys.argv[1]))["frames"]; sys.exit(0 if sum(n != i + 1 for i, n in enumerate(m)) > 100 else 1)' \
  "$WORK/tap.map" || fail "the tap capture is in the original's order: nothing merged"
echo "pcapng_interfaces: office port and TAP captures judged as the original, interfaces reported"
