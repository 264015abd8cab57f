#!/usr/bin/env bash
# What the timing statistics (docs/timing.md) cost `ncservo validate`: a build without them (OLD,
# e.g. main before the timing work) against one with them (NEW) on a simulated 8-axis capture with
# send jitter, every axis decoded (the simulator's layout file), run by run in turn by
# compare_builds.sh; then each build's peak RSS on it. Goal: NEW's frame rate at least 0.95× OLD's
# (timing costs under 5 %), RSS unchanged.
#
# Usage: tests/bench/timing_ratio.sh OLD_NCSERVO NEW_NCSERVO
# Env:   NCSERVO_BENCH_SECONDS  simulated seconds of 1 ms cycles (default 250: 500,000 frames)
#        NCSERVO_BENCH_RUNS     run pairs (default 7)
set -euo pipefail
export LC_ALL=C
[ $# -ge 2 ] || { sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; exit 2; }
old=$1 new=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$new" simulate --scenario soak --no-startup --axes 8 --jitter-us 20 \
  --duration "${NCSERVO_BENCH_SECONDS:-250}" --layout-config "$work/layout.toml" \
  -o "$work/bench.pcap" 2>/dev/null
NCSERVO_BENCH_CMD="validate --format json --output /dev/null --fail-on never --config $work/layout.toml" \
  "$root/tests/bench/compare_builds.sh" "$old" "$new" "$work/bench.pcap"
for build in "$old" "$new"; do
  /usr/bin/time -f "peak RSS %M KiB ($build)" "$build" validate --format json --output /dev/null \
    --fail-on never --config "$work/layout.toml" "$work/bench.pcap" 2>&1 >/dev/null | tail -1
done
