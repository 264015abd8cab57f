#!/usr/bin/env bash
# How long a day's recording takes through a pipe: `ncservo simulate --scenario soak --axes 8
# --cycle-us 250 --duration D -o - | ncservo validate -` (a 4 kHz 8-axis bus, two frames a cycle),
# timed; prints the frame rate and the time 24 hours of that bus would take at that rate, with each
# side's CPU time and the simulator alone (its output to /dev/null), to tell which side limits.
# Goal: a 24-hour recording in under 3 minutes.
#
# Usage: tests/bench/pipe_ratio.sh [BUILD_DIR]     (default: the repository's build/)
# Env:   NCSERVO_BENCH_DURATION  simulated seconds (default 600: 4,800,000 frames)
#        NCSERVO_BENCH_RUNS      runs, taking turns with the simulator alone (default 1): the
#                                fastest of each
# The goal is reported PASS or MISS; the exit status is 0 whatever it is, 1 when a run fails.
# Needs GNU time (/usr/bin/time).
set -euo pipefail
source "$(dirname "$0")/lib.sh"

duration=${NCSERVO_BENCH_DURATION:-600}
runs=${NCSERVO_BENCH_RUNS:-1}
goal_s=180

fail() { echo "pipe_ratio: $*" >&2; exit 1; }
[ -x "$ncservo" ] || fail "no $ncservo (build the ncservo_cli target first)"
/usr/bin/time --version 2>&1 | grep -q GNU || fail "GNU time (/usr/bin/time) is not installed"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

simulate=("$ncservo" simulate --scenario soak --axes 8 --cycle-us 250 --duration "$duration")
now() { date +%s%N; }
best_pipe="" best_sim=""
for _ in $(seq "$runs"); do
  start=$(now)
  /usr/bin/time -f "%U %S" -o "$tmp/sim.cpu" "${simulate[@]}" -o - 2>"$tmp/sim.err" |
    /usr/bin/time -f "%U %S" -o "$tmp/validate.cpu" "$ncservo" validate --fail-on never - \
      >"$tmp/report.txt" || fail "the pipe failed: $(cat "$tmp/sim.err")"
  ns=$(($(now) - start))
  if [ -z "$best_pipe" ] || [ "$ns" -lt "$best_pipe" ]; then
    best_pipe=$ns
    cp "$tmp/sim.cpu" "$tmp/best_sim.cpu"
    cp "$tmp/validate.cpu" "$tmp/best_validate.cpu"
  fi
  start=$(now)
  "${simulate[@]}" -o - 2>/dev/null >/dev/null || fail "simulate failed"
  ns=$(($(now) - start))
  if [ -z "$best_sim" ] || [ "$ns" -lt "$best_sim" ]; then best_sim=$ns; fi
done
frames=$(sed -n 's/^-: \([0-9]*\) frames,.*/\1/p' "$tmp/report.txt")
[ -n "$frames" ] || fail "no frame count in validate's report: $(head -3 "$tmp/report.txt")"
day_frames=$(awk -v f="$frames" -v d="$duration" 'BEGIN { printf "%d", f / d * 86400 }')
cpu() { awk '{ printf "%.2f", $1 + $2 }' "$1"; }
awk -v f="$frames" -v p="$best_pipe" -v s="$best_sim" -v day="$day_frames" -v goal="$goal_s" \
  -v d="$duration" -v sc="$(cpu "$tmp/best_sim.cpu")" -v vc="$(cpu "$tmp/best_validate.cpu")" \
  -v load="$(cut -d' ' -f1-3 /proc/loadavg)" 'BEGIN {
  rate = f / (p / 1e9); sim = f / (s / 1e9); t = day / rate
  printf "simulate | validate -: %d frames (%d s of a 4 kHz 8-axis bus) in %.2f s: %d frames/s\n", f, d, p / 1e9, rate
  printf "  CPU: simulate %.2f s, validate %.2f s; simulate alone (to /dev/null) %.2f s: %d frames/s\n", sc, vc, s / 1e9, sim
  printf "24 hours (%d frames) at that rate: %.1f min (goal under %d min): %s\n", day, t / 60, goal / 60, t < goal ? "PASS" : "MISS"
  printf "(load %s)\n", load
}'
