#!/usr/bin/env bash
# How long `ncservo decode --format vcd` takes against `ncservo validate` on the same capture,
# and how large the VCD is (issue 16: waveforms in less than twice validate's time): a simulated
# 8-axis capture (default 60 s at 1 ms, faults scenario), the two commands taking turns run by
# run; prints each run's wall times, the median of the runs' ratios, the VCD's size and its size
# after vcd2fst (when installed).
#
# Usage: tests/bench/waveform_ratio.sh [BUILD_DIR]     (default: the repository's build/)
# Env:   NCSERVO_BENCH_SECONDS  simulated seconds (default 60)
#        NCSERVO_BENCH_AXES     axes (default 8)
#        NCSERVO_BENCH_RUNS     run pairs (default 3)
# The exit status is 0 whatever the ratio; 1 when a command fails.
set -euo pipefail
export LC_ALL=C

if [ "${1:-}" = -h ] || [ "${1:-}" = --help ]; then
  sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'
  exit 0
fi

root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$root/build}
seconds=${NCSERVO_BENCH_SECONDS:-60}
axes=${NCSERVO_BENCH_AXES:-8}
runs=${NCSERVO_BENCH_RUNS:-3}
ncservo=$build/validator/ncservo
[ -x "$ncservo" ] || { echo "waveform_ratio: no $ncservo" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$ncservo" simulate --scenario faults --axes "$axes" --duration "$seconds" -o "$work/capture.pcap" 2>/dev/null
frames=$("$ncservo" decode --format jsonl --axis 0 "$work/capture.pcap" | wc -l)

# Wall seconds of one command, its output thrown away.
wall() {
  local start end
  start=$(date +%s.%N)
  "$@" >/dev/null 2>&1 || true
  end=$(date +%s.%N)
  echo "$end - $start" | bc -l
}

ratios=()
for run in $(seq "$runs"); do
  v=$(wall "$ncservo" validate --format json --output /dev/null "$work/capture.pcap")
  w=$(wall "$ncservo" decode --format vcd "$work/capture.pcap" -o "$work/waves.vcd")
  r=$(echo "$w / $v" | bc -l)
  ratios+=("$r")
  printf 'run %d: validate %.3f s, decode --format vcd %.3f s, ratio %.2f\n' "$run" "$v" "$w" "$r"
done
median=$(printf '%s\n' "${ratios[@]}" | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}')
size=$(stat -c %s "$work/waves.vcd")
printf 'capture: %d axes, %s s, %d cycles of axis 0; load average %s\n' "$axes" "$seconds" \
  "$frames" "$(cut -d' ' -f1-3 /proc/loadavg)"
printf 'vcd / validate time: %.2f (median of %d; goal below 2)\n' "$median" "$runs"
printf 'VCD: %.1f MiB (%.1f MiB per axis-minute)\n' "$(echo "$size / 1048576" | bc -l)" \
  "$(echo "$size / 1048576 / $axes / ($seconds / 60)" | bc -l)"
if command -v vcd2fst >/dev/null; then
  vcd2fst "$work/waves.vcd" "$work/waves.fst" >/dev/null 2>&1
  printf 'FST (vcd2fst): %.1f MiB\n' "$(echo "$(stat -c %s "$work/waves.fst") / 1048576" | bc -l)"
fi
