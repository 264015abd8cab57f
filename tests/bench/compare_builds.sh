#!/usr/bin/env bash
# Two builds of ncservo on the same capture, run by run in turn (a busy machine's load falls on
# both alike): the new build's frame rate as a ratio of the old one's, the median of the run
# pairs' ratios with the lowest and highest, by wall time and by CPU time (user + system, which a
# busy machine's other processes disturb less). For "no slower than before" goals.
#
# Usage: tests/bench/compare_builds.sh OLD_NCSERVO NEW_NCSERVO [CAPTURE]
# Env:   NCSERVO_BENCH_RUNS    run pairs (default 7)
#        NCSERVO_BENCH_CYCLES  cycles of the generated capture when none is given (default 250000)
#        NCSERVO_BENCH_CMD     ncservo arguments before the capture
#                              (default: validate --format json --output /dev/null)
set -euo pipefail
export LC_ALL=C
[ $# -ge 2 ] || { sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 2; }
old=$1 new=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
runs=${NCSERVO_BENCH_RUNS:-7}
read -r -a args <<<"${NCSERVO_BENCH_CMD:-validate --format json --output /dev/null}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
capture=${3:-}
if [ -z "$capture" ]; then
  capture=$work/bench.pcap
  cycles=${NCSERVO_BENCH_CYCLES:-250000}
  # every axis enabled within the learning window, so that validate infers the layout
  python3 "$root/tests/tools/gen_capture.py" --axes 8 --seed 3 --cycles "$cycles" \
    --enable-by $((cycles / 10 < 2048 ? cycles / 10 : 2048)) -o "$capture" >/dev/null
fi
seconds() {  # BINARY: "WALL CPU" seconds of one run
  local TIMEFORMAT='%3R %3U %3S' times
  times=$({ time "$1" "${args[@]}" "$capture" >/dev/null 2>&1 || [ $? -le 4 ]; } 2>&1)
  read -r wall user sys <<<"$times"
  echo "$wall $(echo "$user + $sys" | bc -l)"
}
"$old" "${args[@]}" "$capture" >/dev/null 2>&1 || true  # page cache
wall_ratios=() cpu_ratios=()
for ((i = 0; i < runs; i++)); do
  read -r wall_old cpu_old <<<"$(seconds "$old")"
  read -r wall_new cpu_new <<<"$(seconds "$new")"
  wall_ratios+=("$(echo "$wall_old / $wall_new" | bc -l)")
  cpu_ratios+=("$(echo "$cpu_old / $cpu_new" | bc -l)")
done
summary() {  # WHAT RATIO...: median, lowest and highest
  local what=$1 sorted median
  shift
  sorted=$(printf '%s\n' "$@" | sort -g)
  median=$(echo "$sorted" | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}')
  printf 'frame rate new/old by %s: %.3fx (median of %d run pairs; lowest %.3f, highest %.3f)\n' \
    "$what" "$median" "$runs" "$(echo "$sorted" | head -1)" "$(echo "$sorted" | tail -1)"
}
summary "wall time" "${wall_ratios[@]}"
summary "CPU time" "${cpu_ratios[@]}"
echo "load $(cut -d' ' -f1 /proc/loadavg)"
