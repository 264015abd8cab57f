#!/usr/bin/env bash
# Where a frame's cost goes in `ncservo validate` (docs/benchmarks.md "Where a frame's cost goes"),
# counted rather than timed: valgrind's callgrind counts the instructions of validate on the
# benchmark's 8-axis capture (tests/tools/gen_capture.py --axes 8 --seed 3 --enable-by 2048, as
# validate_ratio.sh generates it; a tenth of the cycles for N under 40,960) of N and of 2N frames, and prints, per stage, the inclusive
# instructions of its entry point a frame: the difference of the two runs over the N frames
# between them (what a run pays once, such as the learning window's inference, stays out), and
# the longer run's whole count over its frames. Instruction counts do not move with the load of
# a shared machine. One thread (`--read-thread off`), so that the stages add up to the frame: a
# second thread adds the batches' copy and hand-over (docs/benchmarks.md "Two threads").
#
# Usage: tests/bench/frame_cost.sh [BUILD_DIR]     (default: the repository's build/)
# Env:   NCSERVO_BENCH_FRAMES  N, frames of the shorter capture (default 50000; even)
# Needs valgrind (callgrind_annotate) and python3. Exit 1 when a run fails.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

frames=${NCSERVO_BENCH_FRAMES:-50000}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
command -v valgrind >/dev/null || { echo "frame_cost: valgrind not installed" >&2; exit 1; }
[ -x "$ncservo" ] || { echo "frame_cost: no $ncservo (build ncservo_cli first)" >&2; exit 1; }

# Both captures enable the axes alike (by cycle 2048, or a tenth of the shorter one's cycles).
enable_by=$((frames / 20 < 2048 ? frames / 20 : 2048))
for n in "$frames" "$((2 * frames))"; do
  python3 "$root/tests/tools/gen_capture.py" --axes 8 --cycles "$((n / 2))" --seed 3 \
    --enable-by "$enable_by" -o "$work/$n.pcap"
  valgrind --tool=callgrind --callgrind-out-file="$work/$n.out" \
    "$ncservo" validate --read-thread off --format json --output /dev/null "$work/$n.pcap" 2>"$work/valgrind.err" ||
    [ $? = 1 ] || { cat "$work/valgrind.err" >&2; exit 1; }  # 1: validate found something
  callgrind_annotate --inclusive=yes --threshold=100 "$work/$n.out" >"$work/$n.txt"
done

echo "ncservo: $ncservo; load average $(cut -d' ' -f1-3 /proc/loadavg)"
python3 - "$work/$frames.txt" "$frames" "$work/$((2 * frames)).txt" "$((2 * frames))" <<'PY'
import re, sys
# (label, entry point as callgrind names it; "" for the program's total)
STAGES = [
    ("whole run", ""),
    ("reading: libpcap and stdio", "CaptureReader::next("),
    ("walking the datagrams", "ncservo::walkPacket("),
    ("frame clock", "FrameClock::time("),
    ("learning window", "LayoutWindow::hold("),
    ("validator, all", "Validator::onFrame("),
    ("  placements and copy", "Decoder::placeAxes("),
    ("  AL-state tracker", "AlTracker::onFrame("),
    ("  DC clock", "DcClock::onFrame("),
    ("  bus model", "BusModel::onCyclicFrame("),
    ("  measurements: inputs", "AxisMeasurements::takeInputs("),
    ("  measurements: set points", "AxisMeasurements::takeSetPoint("),
    ("  fast path", "Validator::unchanged("),
    ("  axis models", "AxisModel::observe("),
    ("  axis rules", "Validator::evaluateAxis("),
    ("  bus and slave rules", "Validator::reportEvents("),
    ("incident detector", "IncidentDetector::onFrame("),
    ("  its look at the drive faults", "IncidentDetector::takeFaults("),
]

def load(path):
    rows = []
    for line in open(path):
        m = re.match(r"\s*([\d,]+) \([ \d.]+%\)\s+(.*)", line)
        if m:
            rows.append((int(m.group(1).replace(",", "")), m.group(2)))
    return rows

def count(rows, key):
    if not key:
        return next(n for n, name in rows if "PROGRAM TOTALS" in name)
    # the function's own summary lines (its file, then its name); the largest of its entries
    return max([n for n, name in rows if re.search(r":[^ ]*?" + re.escape(key), name.split(" [")[0])]
               or [0])

small, n_small, large, n_large = load(sys.argv[1]), int(sys.argv[2]), load(sys.argv[3]), int(sys.argv[4])
print(f"{'stage':36} {'a frame':>10} {'whole run / frames':>20}")
for label, key in STAGES:
    a, b = count(small, key), count(large, key)
    print(f"{label:36} {(b - a) / (n_large - n_small):10.0f} {b / n_large:20.0f}")
PY
