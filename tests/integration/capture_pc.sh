#!/usr/bin/env bash
# capture_pc.sh SRC BUILD
# What a capturing PC does to a recording (docs/simulate.md#the-capturing-pc), as `ncservo
# simulate` writes it and, apart from it, tests/tools/gen_capture.py, read back by stock tshark
# (frame.time_epoch, frame.interface_id, frame.len, eth.type, sll.etype and each record's bytes):
# --capture-stamps bunched gives bursts at the end of windows of its length, quantised stamps on
# the quantum, late stamps within the length and never back; --duplicate-records each record
# twice, byte for byte, the copy at the same stamp or 1 us later; --second-interface a pcapng of
# two interfaces, link types 1 and 113, the office records between the bus's by time. The bus's
# frames are the plain run's, in order and byte for byte. Without the options both write what
# they always did: simulate_captures and bundled_capture regenerate the bundled captures byte for
# byte. The validator is being taught these captures elsewhere: here only that `ncservo validate`
# reads each to its end (--second-interface: that tshark does).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

# dump CAPTURE: CAPTURE.tsv, one line per record: interface, stamp (ns), length, EtherType (eth
# or sll), bytes (hex), from stock tshark's fields and its hex dump.
dump() {
  local capture=$1
  chmod a+r "$capture"
  "$TSHARK" none -r "$capture" -T fields -e frame.interface_id -e frame.time_epoch -e frame.len \
    -e eth.type -e sll.etype >"$capture.fields" 2>"$WORK/tshark.err" ||
    fail "tshark cannot read $capture: $(cat "$WORK/tshark.err")"
  "$TSHARK" none -r "$capture" -x >"$capture.hex" 2>"$WORK/tshark.err" ||
    fail "tshark cannot dump $capture: $(cat "$WORK/tshark.err")"
  python3 - "$capture" <<'PY' || fail "$capture: tshark's fields and hex dump disagree"
import sys
path = sys.argv[1]
fields = [line.rstrip("\n").split("\t") for line in open(path + ".fields")]
dumps, current = [], []
for line in open(path + ".hex"):
    if not line.strip():
        if current:
            dumps.append("".join(current))
            current = []
        continue
    current.append(line[6:53].replace(" ", ""))  # the offset, then 16 bytes in hex, then ASCII
if current:
    dumps.append("".join(current))
assert len(fields) == len(dumps), (len(fields), len(dumps))
with open(path + ".tsv", "w") as out:
    for (interface, epoch, length, eth, sll), data in zip(fields, dumps):
        seconds, _, fraction = epoch.partition(".")
        ns = int(seconds) * 10**9 + int((fraction + "000000000")[:9])
        assert len(data) == 2 * int(length), (epoch, length, len(data))
        out.write(f"{interface or 0}\t{ns}\t{length}\t{eth or sll}\t{data}\n")  # a pcap: none
PY
}

# check SHAPE LENGTH_NS SHAPED PLAIN: SHAPED.tsv is PLAIN.tsv as the shape makes it.
check() {
  python3 - "$@" <<'PY' || fail "$3 is not what $1 writes: see above"
import sys
shape, length, shaped, plain = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
def rows(path):
    return [(int(i), int(t), int(n), e, d) for i, t, n, e, d in
            (line.rstrip("\n").split("\t") for line in open(path + ".tsv"))]
got, was = rows(shaped), rows(plain)
stamps = [t for _, t, _, _, _ in got]
assert all(a <= b for a, b in zip(stamps, stamps[1:])), "stamps go back"
bus = [r for r in got if r[0] == 0]
if shape == "duplicates":
    assert len(bus) == 2 * len(was), (len(bus), len(was))
    for k in range(0, len(bus), 2):
        original, copy = bus[k], bus[k + 1]
        assert copy[4] == original[4], f"record {k + 2} is not a copy of record {k + 1}"
        assert copy[1] - original[1] in (0, length), f"record {k + 2}: {copy[1] - original[1]} ns"
    bus = bus[::2]
assert [r[4] for r in bus] == [r[4] for r in was], "the bus's frames are not the plain run's"
assert all(r[3] == "0x88a4" for r in bus), "a bus frame that is not EtherCAT"
if shape == "bunched":  # every stamp at the end of its window, a burst's records 2 us apart
    windows = {}
    for (_, passed, _, _, _), (_, t, _, _, _) in zip(was, bus):
        end = (passed // length + 1) * length
        assert end <= t < end + 200_000 and (t - end) % 2000 == 0, (passed, t)
        windows.setdefault(end, []).append(t)
    gaps = sorted(ends for ends in windows)
    assert all(b - a == length for a, b in zip(gaps, gaps[1:])), "a window without a burst"
    assert min(len(burst) for burst in windows.values()) > 2, "bursts of one record"
elif shape == "quantised":  # every stamp on the quantum, several records share one
    assert all(t % length == 0 for _, t, _, _, _ in bus), "a stamp off the quantum"
    assert len({t for _, t, _, _, _ in bus}) * 3 < len(bus), "stamps are not shared"
    assert all(t == p - p % length for (_, p, _, _, _), (_, t, _, _, _) in zip(was, bus))
elif shape == "late":  # late by up to the length, or held back behind the stamp before
    late = [t - p for (_, p, _, _, _), (_, t, _, _, _) in zip(was, bus)]
    assert min(late) >= 0, min(late)
    assert max(late) > length // 2, "the lateness does not spread over the length"
    assert sum(1 for x in late if x > length) < len(late) // 4, "held back too often"
elif shape == "office":  # two interfaces, the office's cooked ARP and IPv4 between the bus's
    office = [r for r in got if r[0] == 1]
    assert len(office) + len(bus) == len(got), "a record on a third interface"
    assert {r[3] for r in office} == {"0x0806", "0x0800"}, {r[3] for r in office}
    seconds = (stamps[-1] - stamps[0]) / 1e9
    assert 100 < len(office) / seconds < 1000, f"{len(office)} office records in {seconds} s"
    assert [r[1] for r in bus] == [r[1] for r in was], "the bus's stamps changed"
    with open(shaped, "rb") as f:  # the IDBs' link types, in the file's own blocks
        data, at, types = f.read(), 0, []
    while at + 12 <= len(data):
        block, size = int.from_bytes(data[at:at + 4], "little"), int.from_bytes(data[at + 4:at + 8], "little")
        if block == 1:
            types.append(int.from_bytes(data[at + 8:at + 10], "little"))
        at += size
    assert types == [1, 113], types
PY
}

# reads CAPTURE: ncservo validate reads it to its end (what it finds is not judged here).
reads() {
  "$NCSERVO" validate --fail-on never "$1" >"$WORK/validate.txt" 2>&1 ||
    fail "validate cannot read $1 (exit $?): $(tail -3 "$WORK/validate.txt")"
}

# The simulator: a 4 kHz bus for the quantised stamps, 1 ms for the rest.
sim() { "$NCSERVO" simulate --axes 2 --duration 1.2 --seed 3 --jitter-us 20 "$@" 2>"$WORK/sim.err" ||
  fail "simulate $*: exit $?: $(cat "$WORK/sim.err")"; }
sim -o "$WORK/sim.pcap"
sim -o "$WORK/sim.pcapng"
sim --cycle-us 250 -o "$WORK/sim-4k.pcap"
sim --capture-stamps bunched:4ms -o "$WORK/sim-bunched.pcap"
sim --cycle-us 250 --capture-stamps quantised:1ms -o "$WORK/sim-quantised.pcap"
sim --capture-stamps late:400us -o "$WORK/sim-late.pcap"
sim --duplicate-records -o "$WORK/sim-duplicates.pcap"
sim --duplicate-records --capture-stamps quantised:1ms -o "$WORK/sim-duplicates-quantised.pcap"
sim --second-interface -o "$WORK/sim-office.pcapng"
for capture in sim sim-4k sim-bunched sim-quantised sim-late sim-duplicates \
  sim-duplicates-quantised; do
  dump "$WORK/$capture.pcap"
done
dump "$WORK/sim.pcapng"
dump "$WORK/sim-office.pcapng"
check bunched 4000000 "$WORK/sim-bunched.pcap" "$WORK/sim.pcap"
check quantised 1000000 "$WORK/sim-quantised.pcap" "$WORK/sim-4k.pcap"
check late 400000 "$WORK/sim-late.pcap" "$WORK/sim.pcap"
check duplicates 1000 "$WORK/sim-duplicates.pcap" "$WORK/sim.pcap"
check duplicates 0 "$WORK/sim-duplicates-quantised.pcap" "$WORK/sim.pcap"  # a coarse clock: the same stamp
check office 0 "$WORK/sim-office.pcapng" "$WORK/sim.pcapng"
for capture in sim-bunched sim-quantised sim-late sim-duplicates; do reads "$WORK/$capture.pcap"; done

# The same options, the same bytes; the seed draws the late stamps and the office's records.
sim --capture-stamps late:400us -o "$WORK/again.pcap"
cmp -s "$WORK/again.pcap" "$WORK/sim-late.pcap" || fail "--capture-stamps late: another run, other bytes"
"$NCSERVO" simulate --axes 2 --duration 1.2 --seed 4 --jitter-us 20 --second-interface \
  -o "$WORK/other.pcapng" 2>/dev/null
! cmp -s "$WORK/other.pcapng" "$WORK/sim-office.pcapng" || fail "--second-interface: another seed, the same bytes"

# A capture that begins inside SE-003's fault: axis 2's first cycles hold ServoEn with no enable
# requested (SE not 0x2), as decode reads them with the simulator's layout.
"$NCSERVO" simulate --start-in fault:SE-003 --fault SE-003@1.0:2 -o "$WORK/in-fault.pcap" \
  --layout-config "$WORK/in-fault.toml" 2>"$WORK/sim.err" || fail "--start-in: $(cat "$WORK/sim.err")"
dump "$WORK/in-fault.pcap"
"$NCSERVO" decode --config "$WORK/in-fault.toml" --axis 2 "$WORK/in-fault.pcap" >"$WORK/in-fault.csv"
python3 - "$WORK/in-fault.csv" <<'PY' || fail "the capture does not begin inside SE-003's fault"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))[:10]
assert len(rows) == 10, len(rows)
for row in rows:
    assert row["scw.se"] != "2" and row["ssw.servo_en"] == "1", row
PY

# The generator, written apart from the simulator: the same shapes by its own code.
gen() { python3 "$GEN" --axes 2 --cycles 1200 --seed 3 "$@" 2>"$WORK/gen.err" ||
  fail "gen_capture $*: exit $?: $(cat "$WORK/gen.err")"; }
gen -o "$WORK/gen.pcap"
gen --format pcapng -o "$WORK/gen.pcapng"
gen --cycle-us 250 --cycles 4000 -o "$WORK/gen-4k.pcap"
gen --capture-stamps bunched:4ms -o "$WORK/gen-bunched.pcap"
gen --cycle-us 250 --cycles 4000 --capture-stamps quantised:1ms -o "$WORK/gen-quantised.pcap"
gen --capture-stamps late:400us -o "$WORK/gen-late.pcap"
gen --duplicate-records -o "$WORK/gen-duplicates.pcap"
gen --format pcapng --second-interface -o "$WORK/gen-office.pcapng"
for capture in gen gen-4k gen-bunched gen-quantised gen-late gen-duplicates; do
  dump "$WORK/$capture.pcap"
done
dump "$WORK/gen.pcapng"
dump "$WORK/gen-office.pcapng"
check bunched 4000000 "$WORK/gen-bunched.pcap" "$WORK/gen.pcap"
check quantised 1000000 "$WORK/gen-quantised.pcap" "$WORK/gen-4k.pcap"
check late 400000 "$WORK/gen-late.pcap" "$WORK/gen.pcap"
check duplicates 1000 "$WORK/gen-duplicates.pcap" "$WORK/gen.pcap"
check office 0 "$WORK/gen-office.pcapng" "$WORK/gen.pcapng"
for capture in gen-bunched gen-quantised gen-late gen-duplicates; do reads "$WORK/$capture.pcap"; done

# Options that do not go together end with exit 2 and say why.
cases=(
  "2|--second-interface: a pcap holds one interface; write a pcapng|simulate --second-interface -o $WORK/x.pcap"
  "2|--capture-stamps bunched:50us: a burst window from 100 us to 100 ms|simulate --capture-stamps bunched:50us -o $WORK/x.pcap"
  "2|--capture-stamps late:4: expected SHAPE:LENGTH|simulate --capture-stamps late:4 -o $WORK/x.pcap"
  "2|--start-in fault:SE-001: SE-001's fault has no standing condition to begin inside; one of SE-003, FLT-001|simulate --start-in fault:SE-001 -o $WORK/x.pcap"
)
for row in "${cases[@]}"; do
  IFS='|' read -r want message args <<<"$row"
  read -r -a argv <<<"$args"
  set +e
  "$NCSERVO" "${argv[@]}" >"$WORK/out.txt" 2>"$WORK/err.txt"
  rc=$?
  set -e
  [ "$rc" = "$want" ] || fail "ncservo $args: exit $rc, expected $want: $(cat "$WORK/err.txt")"
  grep -qF -- "$message" "$WORK/err.txt" || fail "ncservo $args: no '$message' in: $(cat "$WORK/err.txt")"
done
set +e
python3 "$GEN" --second-interface -o "$WORK/x.pcap" 2>"$WORK/err.txt"
rc=$?
set -e
[ "$rc" = 2 ] && grep -qF -- "--second-interface: a pcap holds one interface" "$WORK/err.txt" ||
  fail "gen_capture --second-interface into a pcap: exit $rc: $(cat "$WORK/err.txt")"
echo "capture_pc: simulate and gen_capture write bursts, quanta, late stamps, copies and an office port; a start inside SE-003"
