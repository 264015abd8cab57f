#!/usr/bin/env bash
# dc_truth.sh SRC BUILD
# Distributed clocks (docs/timing.md) on the real captures that read them, against stock tshark
# without the plugin: its EtherCAT dissector's register fields for the system time (0x0910,
# ecat.reg.dc.systime) and the system time difference (0x092C, ecat.reg.dc.ctrlerr, shown raw)
# of every returned copy some slave answered. From that dump this script computes, on its own,
# each station's drift (least squares of system time − frame time over frame time, fitted again
# after a write of the system time offset 0x0920), the last and largest |difference| (bit 31 the
# sign) and the frame from which every later difference stayed within 100 ns, and compares them
# with `validate --format json`'s `timing.dc`. A capture without DC reads has an empty list.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_path "$REAL_CAPTURES" "real captures"
real=$REAL_CAPTURES

check() {  # CAPTURE EXPECTED_STATIONS
  local capture=$real/$1 stations=$2 name=$1
  tshark -r "$capture" -T fields -E occurrence=a -E aggregator=';' -e frame.number \
    -e frame.time_epoch -e eth.src -e ecat.cmd -e ecat.adp -e ecat.ado -e ecat.cnt -e ecat.subframe.length \
    -e ecat.reg.dc.systime -e ecat.reg.dc.ctrlerr >"$WORK/$name.tsv" 2>"$WORK/tshark.err" ||
    fail "$name: tshark exited $?: $(head -3 "$WORK/tshark.err")"
  "$NCSERVO" validate --format json --fail-on never --allow-empty "$capture" >"$WORK/$name.json" ||
    fail "$name: validate exited $?"
  python3 - "$WORK/$name.tsv" "$WORK/$name.json" "$stations" <<'PY' || fail "$name: see above"
import json, sys
from decimal import Decimal

FPRD, FPWR, FPRW, BWR, FRMW = 0x04, 0x05, 0x06, 0x08, 0x0E
SYSTIME, OFFSET, DIFFERENCE, BOUND = 0x0910, 0x0920, 0x092C, 100
samples, diffs = {}, {}  # station -> [(t_ns, systime)], [(frame, signed ns)]
for line in open(sys.argv[1]):
    f = line.rstrip("\n").split("\t")
    if len(f) < 10 or not f[3]:
        continue
    frame, t_ns = int(f[0]), int(Decimal(f[1]) * 10**9)
    returned = int(f[2].split(":")[0], 16) & 0x02 != 0  # slaves set the locally-administered bit
    cmds, adps, ados, cnts, lens = ([int(v, 0) for v in c.split(";")] for c in f[3:8])
    times = [int(v, 16) for v in f[8].split(";") if v]
    ctrl = [int(v, 16) for v in f[9].split(";") if v]
    # One register value per datagram at that register (returned copies): which datagram showed
    # it is then known.
    at_time = [i for i, a in enumerate(ados) if a <= SYSTIME and a + lens[i] >= SYSTIME + 8]
    at_diff = [i for i, a in enumerate(ados) if a <= DIFFERENCE and a + lens[i] >= DIFFERENCE + 4]
    for i, c in enumerate(cmds):
        if not returned and c in (FPWR, FPRW, BWR) and ados[i] <= OFFSET < ados[i] + lens[i]:
            for station in samples:
                if c == BWR or station == adps[i]:
                    samples[station] = []
    if not returned:
        continue
    # A datagram no slave answered may come back without its register shown.
    if len(at_time) != len(times):
        at_time = [i for i in at_time if cnts[i] > 0]
    if len(at_diff) != len(ctrl):
        at_diff = [i for i in at_diff if cnts[i] > 0]
    assert len(at_time) == len(times) and len(at_diff) == len(ctrl), (frame, f)
    for k, i in enumerate(at_time):
        if cmds[i] in (FRMW, FPRD) and cnts[i] > 0:
            samples.setdefault(adps[i], []).append((t_ns, times[k]))
    for k, i in enumerate(at_diff):
        if cmds[i] == FPRD and cnts[i] > 0:
            raw = ctrl[k]
            signed = -(raw & 0x7FFFFFFF) if raw & 0x80000000 else raw
            diffs.setdefault(adps[i], []).append((frame, signed))

def drift_ppm(points):
    if len(points) < 2:
        return None
    t0, s0 = points[0]
    xs = [(t - t0) / 1e9 for t, _ in points]
    ys = [(s - s0) - (t - t0) for t, s in points]
    n, mx, my = len(xs), sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx / 1000.0

def settled(reads):
    frame = None
    for f, v in reads:
        if abs(v) > BOUND:
            frame = None
        elif frame is None:
            frame = f
    return frame

dc = json.load(open(sys.argv[2]))["captures"][0]["timing"]["dc"]
got = {int(e["station"], 16): e for e in dc}
want = sorted(set(samples) | set(diffs))
assert sorted(got) == want, (sorted(got), want)
assert want == [int(s, 16) for s in sys.argv[3].split()], (want, sys.argv[3])
for station in want:
    e, points, reads = got[station], samples.get(station, []), diffs.get(station, [])
    assert e["samples"] == len(points), (hex(station), e["samples"], len(points))
    assert e["reference"] == (station in samples), e
    d = drift_ppm(points)
    if d is None:
        assert e["drift_ppm"] is None, e
    else:
        assert abs(e["drift_ppm"] - d) < 0.002 + abs(d) * 1e-6, (hex(station), e["drift_ppm"], d)
    if not reads:
        assert e["systime_diff_ns"] is None and e["settled_frame"] is None, e
        continue
    s = e["systime_diff_ns"]
    assert s["last"] == reads[-1][1] and s["reads"] == len(reads), (hex(station), s, reads)
    assert s["max_abs"] == max(abs(v) for _, v in reads), (hex(station), s, reads)
    assert e["settled_frame"] == settled(reads), (hex(station), e["settled_frame"], reads)
    print(f"{hex(station)}: drift {e['drift_ppm']} ppm over {len(points)} reads, "
          f"difference {s}, settled {e['settled_frame']}")
PY
}

check ethercrab-dc-to-op.pcapng "0x1000 0x1002"
check ethercrab-outputs-to-op.pcapng "0x1000"
# Only broadcast reads of 0x0910 there: they name no slave.
check wiki-beckhoff-startup.cap ""
check soem-akd-servo-pdo-mapping.pcapng ""

# The simulator's master reads the first slave's system time with FRMW in every cycle, from the
# clock that stamps the capture: one reference clock without drift, a sample per returned FRMW.
"$NCSERVO" simulate --axes 2 --duration 1 -o "$WORK/sim.pcap" 2>/dev/null
frmw=$(tshark -r "$WORK/sim.pcap" -Y 'ecat.cmd == 0x0e && ecat.ado == 0x0910 && ecat.cnt > 0' \
  -T fields -e frame.number 2>/dev/null | wc -l)
"$NCSERVO" validate --format json --fail-on never "$WORK/sim.pcap" >"$WORK/sim.json" ||
  fail "simulated: validate exited $?"
python3 - "$WORK/sim.json" "$frmw" <<'PY' || fail "simulated capture: timing.dc"
import json, sys
dc = json.load(open(sys.argv[1]))["captures"][0]["timing"]["dc"]
assert len(dc) == 1 and int(sys.argv[2]) > 900, (dc, sys.argv[2])
e = dc[0]
assert (e["station"], e["reference"], e["samples"]) == ("0x03E9", True, int(sys.argv[2])), e
assert e["drift_ppm"] == e["drift_first_half_ppm"] == e["drift_second_half_ppm"] == 0.0, e
assert e["systime_diff_ns"] is None and e["settled_frame"] is None, e
PY
echo "dc_truth: timing.dc agrees with stock tshark's register fields"
