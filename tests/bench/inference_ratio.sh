#!/usr/bin/env bash
# What inferring the layout costs (docs/protocol.md §9.4): `ncservo validate` on a simulated
# 2,000,000-frame capture without a start-up, with no configuration (the learning window holds the
# first frames, infers the layout and replays them) against the same with --config (the
# simulator's exact layout file), and the peak RSS of both.
# Goals: the inferred run's frame rate at least 0.95x the configured run's; peak RSS under 32 MiB.
#
# Usage: tests/bench/inference_ratio.sh [BUILD_DIR]     (default: the repository's build/)
# Env:   NCSERVO_BENCH_SECONDS  simulated seconds at 1 kHz, 2 frames a cycle (default 1000)
#        NCSERVO_BENCH_AXES     servo axes (default 8)
#        NCSERVO_BENCH_RUNS     runs per measurement, taking turns (default 3): best wall time,
#                               highest RSS
# The goals are reported PASS or MISS; the exit status is 0 whatever they are, 1 when a run fails.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

seconds=${NCSERVO_BENCH_SECONDS:-1000}
axes=${NCSERVO_BENCH_AXES:-8}
runs=${NCSERVO_BENCH_RUNS:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$ncservo" simulate --scenario soak --no-startup --axes "$axes" --duration "$seconds" --seed 7 \
  -o "$work/capture.pcap" --layout-config "$work/layout.toml" 2>/dev/null
frames=$(( seconds * 2000 ))

measure() {  # NAME ARGS...: prints "wall_s rss_kib" of one run
  /usr/bin/time -f "%e %M" -o "$work/time" "$ncservo" validate --format json --output /dev/null \
    --fail-on never "$@" "$work/capture.pcap" || { echo "ncservo failed" >&2; exit 1; }
  cat "$work/time"
}

best_inferred=999999 best_config=999999 rss_inferred=0 rss_config=0
for _ in $(seq "$runs"); do
  read -r wall rss < <(measure)
  best_inferred=$(awk -v a="$best_inferred" -v b="$wall" 'BEGIN{print (b<a)?b:a}')
  rss_inferred=$(( rss > rss_inferred ? rss : rss_inferred ))
  read -r wall rss < <(measure --config "$work/layout.toml")
  best_config=$(awk -v a="$best_config" -v b="$wall" 'BEGIN{print (b<a)?b:a}')
  rss_config=$(( rss > rss_config ? rss : rss_config ))
done
ratio=$(awk -v i="$best_inferred" -v c="$best_config" 'BEGIN{printf "%.3f", (i>0)?c/i:0}')
goal() { [ "$1" = 1 ] && echo PASS || echo MISS; }
printf "capture: %d frames, %d axes, no start-up (load %s)\n" "$frames" "$axes" "$(cut -d' ' -f1-3 /proc/loadavg)"
printf "inferred: %.2f s (%.0f frames/s), peak RSS %d KiB\n" "$best_inferred" "$(awk -v f="$frames" -v t="$best_inferred" 'BEGIN{print f/t}')" "$rss_inferred"
printf "config:   %.2f s (%.0f frames/s), peak RSS %d KiB\n" "$best_config" "$(awk -v f="$frames" -v t="$best_config" 'BEGIN{print f/t}')" "$rss_config"
printf "rate inferred/config: %s (goal >= 0.95): %s\n" "$ratio" "$(goal "$(awk -v r="$ratio" 'BEGIN{print (r>=0.95)?1:0}')")"
printf "peak RSS under 32 MiB: %s\n" "$(goal $(( rss_inferred < 32768 && rss_config < 32768 ? 1 : 0 )))"
