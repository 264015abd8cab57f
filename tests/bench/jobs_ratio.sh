#!/usr/bin/env bash
# `validate --jobs`: 20 simulated captures validated with --jobs 1 and with --jobs N;
# prints both wall times and their ratio, and checks that the two outputs are byte-identical.
# Goal: faster with --jobs 2 on two cores (ratio above 1). The machine may be busy: the load
# average is printed, and the best of the runs is kept.
#
# Usage: tests/bench/jobs_ratio.sh [BUILD_DIR]       (default: the repository's build/)
# Env:   NCSERVO_BENCH_JOBS      N (default 2)
#        NCSERVO_BENCH_CAPTURES  how many captures (default 20)
#        NCSERVO_BENCH_DURATION  seconds of each simulated capture (default 60)
#        NCSERVO_BENCH_RUNS      runs per measurement (default 3)
set -euo pipefail
source "$(dirname "$0")/lib.sh"

jobs=${NCSERVO_BENCH_JOBS:-2}
count=${NCSERVO_BENCH_CAPTURES:-20}
duration=${NCSERVO_BENCH_DURATION:-60}
runs=${NCSERVO_BENCH_RUNS:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

captures=()
for i in $(seq 1 "$count"); do
  scenario=commissioning
  [ $((i % 2)) = 0 ] && scenario=faults
  "$ncservo" simulate --scenario "$scenario" --duration "$duration" --seed "$i" \
    -o "$work/c$i.pcap" 2>/dev/null
  captures+=("$work/c$i.pcap")
done

# best J: the best wall time of `runs` runs with --jobs J, in seconds; the output in $work/out.J
best() {
  local j=$1 best_s="" start end s
  for _ in $(seq 1 "$runs"); do
    start=$(date +%s.%N)
    "$ncservo" validate --format json --fail-on never --jobs "$j" "${captures[@]}" >"$work/out.$j"
    end=$(date +%s.%N)
    s=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.3f", b - a }')
    if [ -z "$best_s" ] || awk -v a="$s" -v b="$best_s" 'BEGIN { exit !(a < b) }'; then best_s=$s; fi
  done
  echo "$best_s"
}

echo "load average: $(cut -d' ' -f1-3 /proc/loadavg); cores: $(nproc)"
serial=$(best 1)
parallel=$(best "$jobs")
cmp -s "$work/out.1" "$work/out.$jobs" || { echo "FAIL: --jobs $jobs output differs from --jobs 1"; exit 1; }
ratio=$(awk -v a="$serial" -v b="$parallel" 'BEGIN { printf "%.2f", a / b }')
echo "$count captures of ${duration} s: --jobs 1 ${serial} s, --jobs $jobs ${parallel} s: ratio ${ratio}x (outputs identical)"
awk -v r="$ratio" 'BEGIN { exit !(r > 1) }' && echo "PASS: faster with --jobs $jobs" ||
  echo "MISS: not faster with --jobs $jobs (a busy machine?)"
