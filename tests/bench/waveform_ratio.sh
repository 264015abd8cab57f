#!/usr/bin/env bash
# How long `ncservo decode --format vcd` and `ncservo validate --format html` take against
# `ncservo validate` on the same capture, and how large the VCD and the page are (goal: each
# in less than twice validate's time): a simulated 8-axis capture (default 60 s at 1 ms, faults
# scenario), the three commands taking turns run by run; prints each run's wall and CPU
# (user + system) times, the medians of the runs' ratios, the sizes, and the VCD's size after
# vcd2fst (when installed). On a machine shared with other jobs the CPU ratio is the steadier one:
# the wall time also counts the time spent waiting for a CPU.
#
# Usage: tests/bench/waveform_ratio.sh [BUILD_DIR]     (default: the repository's build/)
# Env:   NCSERVO_BENCH_SECONDS  simulated seconds (default 60)
#        NCSERVO_BENCH_AXES     axes (default 8)
#        NCSERVO_BENCH_RUNS     run pairs (default 3)
# The exit status is 0 whatever the ratio; 1 when a command fails.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

seconds=${NCSERVO_BENCH_SECONDS:-60}
axes=${NCSERVO_BENCH_AXES:-8}
runs=${NCSERVO_BENCH_RUNS:-3}
[ -x "$ncservo" ] || { echo "waveform_ratio: no $ncservo" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$ncservo" simulate --scenario faults --axes "$axes" --duration "$seconds" -o "$work/capture.pcap" 2>/dev/null
frames=$("$ncservo" decode --format jsonl --axis 0 "$work/capture.pcap" | wc -l)

# "WALL CPU" seconds of one command, its output thrown away.
timed() {
  /usr/bin/time -f '%e %U %S' -o "$work/time" "$@" >/dev/null 2>&1 || true
  tail -1 "$work/time" | awk '{printf "%s %.3f\n", $1, $2 + $3}'
}

ratios=() cpu_ratios=() html_ratios=() html_cpu_ratios=()
for run in $(seq "$runs"); do
  read -r v vc < <(timed "$ncservo" validate --format json --output /dev/null "$work/capture.pcap")
  read -r w wc < <(timed "$ncservo" decode --format vcd "$work/capture.pcap" -o "$work/waves.vcd")
  read -r h hc < <(timed "$ncservo" validate --format html --output "$work/report.html" "$work/capture.pcap")
  ratios+=("$(echo "$w / $v" | bc -l)") cpu_ratios+=("$(echo "$wc / $vc" | bc -l)")
  html_ratios+=("$(echo "$h / $v" | bc -l)") html_cpu_ratios+=("$(echo "$hc / $vc" | bc -l)")
  printf 'run %d: validate %.3f s (CPU %.3f), vcd %.3f s (CPU %.3f), html %.3f s (CPU %.3f)\n' \
    "$run" "$v" "$vc" "$w" "$wc" "$h" "$hc"
done
median_of() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
printf 'capture: %d axes, %s s, %d cycles of axis 0; load average %s\n' "$axes" "$seconds" \
  "$frames" "$(cut -d' ' -f1-3 /proc/loadavg)"
printf 'vcd / validate time: %.2f wall, %.2f CPU (medians of %d; goal below 2)\n' \
  "$(median_of "${ratios[@]}")" "$(median_of "${cpu_ratios[@]}")" "$runs"
printf 'html / validate time: %.2f wall, %.2f CPU (medians of %d; goal below 2)\n' \
  "$(median_of "${html_ratios[@]}")" "$(median_of "${html_cpu_ratios[@]}")" "$runs"
size=$(stat -c %s "$work/waves.vcd")
printf 'HTML: %.2f MiB\n' "$(echo "$(stat -c %s "$work/report.html") / 1048576" | bc -l)"
printf 'VCD: %.1f MiB (%.1f MiB per axis-minute)\n' "$(echo "$size / 1048576" | bc -l)" \
  "$(echo "$size / 1048576 / $axes / ($seconds / 60)" | bc -l)"
if command -v vcd2fst >/dev/null; then
  vcd2fst "$work/waves.vcd" "$work/waves.fst" >/dev/null 2>&1
  printf 'FST (vcd2fst): %.1f MiB\n' "$(echo "$(stat -c %s "$work/waves.fst") / 1048576" | bc -l)"
fi
