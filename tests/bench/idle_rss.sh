#!/usr/bin/env bash
# How much memory inferring the layout takes when the capture starts idle (docs/layout.md: the
# drives ready, nothing enabled, so no handshake decides early): `ncservo validate` with no
# configuration on a simulated 2,000,000-frame 8-axis capture without a start-up that stays idle
# for its first half, its peak RSS (GNU time) against the 32 MiB goal and against the same run
# with --config (the simulator's exact layout file), in the same run; and where the layout
# became certain.
# Goal: peak RSS under 32 MiB with no configuration.
#
# Usage: tests/bench/idle_rss.sh [BUILD_DIR]     (default: the repository's build/)
# Env:   NCSERVO_BENCH_SECONDS    simulated seconds at 1 kHz, 2 frames a cycle (default 1000); the
#                                 first half idle
#        NCSERVO_BENCH_AXES       servo axes (default 8)
#        NCSERVO_BENCH_RUNS       runs per measurement, taking turns (default 3): highest RSS
#        NCSERVO_BENCH_GENERATOR  1: also the independent generator's capture of the same shape
#                                 (tests/tools/gen_capture.py --idle-cycles; minutes to write)
# The goal is reported PASS or MISS; the exit status is 0 whatever it is, 1 when a run fails.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

seconds=${NCSERVO_BENCH_SECONDS:-1000}
axes=${NCSERVO_BENCH_AXES:-8}
runs=${NCSERVO_BENCH_RUNS:-3}
generator=${NCSERVO_BENCH_GENERATOR:-0}
goal_rss_kib=$((32 * 1024))
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

fail() { echo "idle_rss: $*" >&2; exit 1; }
[ -x "$ncservo" ] || fail "no $ncservo (build the ncservo_cli target first)"
[ -x /usr/bin/time ] || fail "GNU time (/usr/bin/time) is not installed"

cycles=$((seconds * 1000))
frames=$((cycles * 2))
"$ncservo" simulate --scenario soak --no-startup --axes "$axes" --duration "$seconds" \
  --idle $((seconds / 2)) --seed 7 -o "$work/sim.pcap" --layout-config "$work/sim.toml" \
  2>/dev/null || fail "simulate failed"
captures=(sim)
if [ "$generator" = 1 ]; then
  python3 "$root/tests/tools/gen_capture.py" --axes "$axes" --cycles "$cycles" \
    --idle-cycles $((cycles / 2)) --seed 3 -o "$work/gen.pcap" --layout-config "$work/gen.toml" ||
    fail "gen_capture.py failed"
  captures+=(gen)
fi

rss() {  # CAPTURE ARGS...: the peak RSS of one run, in KiB
  local capture=$1
  shift
  /usr/bin/time -v -o "$work/time" "$ncservo" validate --format json --output /dev/null \
    --fail-on never "$@" "$work/$capture.pcap" || fail "validate $* $capture.pcap failed"
  sed -n 's/^[[:space:]]*Maximum resident set size (kbytes): //p' "$work/time"
}

goal() { [ "$1" = 1 ] && echo PASS || echo MISS; }
printf "captures: %d frames, %d axes, no start-up, idle for the first %d s (load %s)\n" \
  "$frames" "$axes" $((seconds / 2)) "$(cut -d' ' -f1-3 /proc/loadavg)"
for capture in "${captures[@]}"; do
  free=0 configured=0
  for _ in $(seq "$runs"); do
    r=$(rss "$capture")
    free=$((r > free ? r : free))
    r=$(rss "$capture" --config "$work/$capture.toml")
    configured=$((r > configured ? r : configured))
  done
  "$ncservo" validate --fail-on never "$work/$capture.pcap" >"$work/$capture.txt" 2>&1 || true
  layout=$(grep -m1 '^layout:' "$work/$capture.txt" || echo "layout: ?")
  how=$(grep -m1 -E 'certain at|inferred:' "$work/$capture.txt" | sed 's/^[[:space:]]*//' || true)
  printf "%s: %s%s\n" "$capture" "$layout" "${how:+ ($how)}"
  printf "%s: peak RSS %d KiB (%.1f MiB) with no configuration, %d KiB with --config: %.2fx\n" \
    "$capture" "$free" "$(awk -v k="$free" 'BEGIN{print k/1024}')" "$configured" \
    "$(awk -v a="$free" -v b="$configured" 'BEGIN{print (b>0)?a/b:0}')"
  printf "%s: peak RSS under 32 MiB: %s (%.2f of the goal)\n" "$capture" \
    "$(goal $((free < goal_rss_kib ? 1 : 0)))" \
    "$(awk -v k="$free" -v g="$goal_rss_kib" 'BEGIN{print k/g}')"
done
