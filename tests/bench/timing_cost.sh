#!/usr/bin/env bash
# What the timing statistics (docs/timing.md) cost `ncservo validate`, counted rather than timed:
# valgrind's callgrind counts the instructions of one run on a simulated 8-axis capture with send
# jitter and return latency, every axis decoded (the simulator's layout file), and the share spent
# inside the timing entry points (TimingStats::onCycle, onLatency and summary, with everything
# they call) is printed; beside it, the share of following the distributed clocks
# (DcClock::onFrame and stations; the simulator reads the reference clock every cycle).
# Instruction counts do not depend on the load of a shared machine, where wall-time ratios of two
# builds spread wider than the goal. Goal: statistics under 5 %. The peak RSS of two capture
# lengths shows the statistics' memory is bounded (exact samples stop at 65,536).
#
# Usage: tests/bench/timing_cost.sh [BUILD_DIR]     (default: the repository's build/)
# Env:   NCSERVO_BENCH_SECONDS  simulated seconds of 1 ms cycles (default 50: 100,000 frames)
# Needs valgrind (callgrind_annotate) and GNU time. Exit 0 whatever the share; 1 when a run fails.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

seconds=${NCSERVO_BENCH_SECONDS:-50}
goal_percent=5
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
command -v valgrind >/dev/null || { echo "timing_cost: valgrind not installed" >&2; exit 1; }

simulate() {  # simulate SECONDS OUT
  "$ncservo" simulate --scenario soak --no-startup --axes 8 --jitter-us 20 --latency-us 40 \
    --duration "$1" --layout-config "$work/layout.toml" -o "$2" 2>/dev/null
}
validate=(validate --format json --output "$work/report.json" --fail-on never
  --config "$work/layout.toml")

simulate "$seconds" "$work/bench.pcap"
valgrind --tool=callgrind --callgrind-out-file="$work/callgrind.out" \
  "$ncservo" "${validate[@]}" "$work/bench.pcap" 2>"$work/valgrind.err" ||
  { cat "$work/valgrind.err" >&2; exit 1; }
callgrind_annotate --inclusive=yes --threshold=100 "$work/callgrind.out" >"$work/annotated.txt"
awk -v goal="$goal_percent" -v frames="$((seconds * 2000))" '
  function count(s) { gsub(",", "", s); return s + 0 }
  / PROGRAM TOTALS/ { total = count($1) }
  # The summary line of a function names its object file; call lines start with "=>".
  /ncservo::TimingStats::(onCycle|onLatency|summary)\(.*\[/ && !/=>/ {
    n = count($1); timing += n
    name = $0; sub(/^[^:]*:ncservo::/, "", name); sub(/ \[.*/, "", name)
    printf "  %-62s %12d instructions\n", name, n
  }
  /ncservo::DcClock::(onFrame|stations)\(.*\[/ && !/=>/ {
    n = count($1); dc += n
    name = $0; sub(/^[^:]*:ncservo::/, "", name); sub(/ \[.*/, "", name)
    printf "  %-62s %12d instructions\n", name, n
  }
  END {
    if (total == 0) { print "timing_cost: no program totals" > "/dev/stderr"; exit 1 }
    share = 100 * timing / total
    printf "validate: %d instructions, %.0f a frame over %d frames\n", total, total / frames, frames
    printf "timing statistics: %d instructions = %.2f %% (goal < %d %%): %s\n", timing, share,
      goal, share < goal ? "PASS" : "MISS"
    printf "distributed clocks (a 0x0910 read every cycle): %d instructions = %.2f %%\n", dc,
      100 * dc / total
  }' "$work/annotated.txt"

simulate "$((seconds * 4))" "$work/long.pcap"
for capture in bench long; do
  /usr/bin/time -f "peak RSS %M KiB" "$ncservo" "${validate[@]}" "$work/$capture.pcap" 2>&1 |
    tail -1 | sed "s/^/$capture ($(stat -c %s "$work/$capture.pcap") bytes): /"
done
