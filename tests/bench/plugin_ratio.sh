#!/usr/bin/env bash
# What the ncservo plugin costs: tshark extracting the ncservo fields from a long 8-axis
# capture, against the same tshark without the plugin extracting the stock EtherCAT fields.
# Usage: tests/bench/plugin_ratio.sh [BUILD_DIR]          (default: build)
# Env:   NCSERVO_BENCH_CYCLES  cycles in the capture (default 200000 = 400000 frames)
#        NCSERVO_BENCH_GOAL    highest acceptable plugin/baseline ratio (default 1.30)
#        NCSERVO_BENCH_RUNS    runs of each side, alternated; the median counts (default 3)
#        NCSERVO_BENCH_FLOOR=1 also time the item floor (BUILD_DIR/plugin/ncservo_item_floor.so,
#                              built here): the plugin's first pass and items with
#                              constant texts, i.e. what Wireshark itself spends on the items
# Exit 1 when the ratio is above the goal, 2 when a run fails.
set -euo pipefail
export LC_ALL=C  # decimal points in date, bc and printf

root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-build}
cycles=${NCSERVO_BENCH_CYCLES:-200000}
goal=${NCSERVO_BENCH_GOAL:-1.30}
runs=${NCSERVO_BENCH_RUNS:-3}
floor_wanted=${NCSERVO_BENCH_FLOOR:-0}
runner=$root/tests/tools/tshark-with-plugin.sh
plugin=$(realpath "$build/plugin/ncservo.so" 2>/dev/null || true)
if [ -z "$plugin" ] || [ ! -f "$plugin" ]; then
  echo "plugin_ratio: no $build/plugin/ncservo.so (build first)" >&2
  exit 2
fi
floor=
if [ "$floor_wanted" = 1 ]; then
  if ! cmake --build "$build" --target ncservo_item_floor >&2; then
    echo "plugin_ratio: cannot build the item floor plugin in $build" >&2
    exit 2
  fi
  floor=$(realpath "$build/plugin/ncservo_item_floor.so")
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# as root the runner drops to user nobody, which must be able to read the capture
chmod a+rx "$tmp"
cap=$tmp/bench.pcap
python3 "$root/tests/tools/gen_capture.py" --axes 8 --cycles "$cycles" -o "$cap"
chmod a+r "$cap"

baseline=(none -r "$cap" -T fields -e ecat.cmd -e ecat.lad -e ecat.cnt -e ecat.data)
ncservo_fields=(-T fields -e ncservo.ssp -e ncservo.scw -e ncservo.ext_code -e ncservo.actpos
                -e ncservo.ssw -e ncservo.sew -e ncservo.msg_code -e ncservo.msg_data)
with_plugin=("$plugin" -r "$cap" "${ncservo_fields[@]}")
with_floor=("$floor" -r "$cap" "${ncservo_fields[@]}")

run() { # run ARGS... > OUT: the runner, failing loudly with tshark's messages
  if ! "$runner" "$@" 2>"$tmp/stderr"; then
    echo "plugin_ratio: tshark-with-plugin.sh $* failed:" >&2
    cat "$tmp/stderr" >&2
    exit 2
  fi
}

# The default layout needs a repeated datagram before it decodes, so not every one of the
# first frames has to carry fields; most of them must, and some must carry inputs.
sanity_check() {
  run "${with_plugin[@]}" -c 20 >"$tmp/first.tsv"
  local with_outputs with_inputs
  with_outputs=$(awk -F'\t' '$1 != ""' "$tmp/first.tsv" | wc -l)
  with_inputs=$(awk -F'\t' '$5 != ""' "$tmp/first.tsv" | wc -l)
  if [ "$with_outputs" -lt 10 ] || [ "$with_inputs" -lt 5 ]; then
    echo "plugin_ratio: the plugin decoded too little of the first 20 frames" \
      "($with_outputs with outputs, $with_inputs with inputs):" >&2
    head -n 5 "$tmp/first.tsv" >&2
    exit 2
  fi
}

wall() { # wall ARGS...: prints the seconds one run takes
  local start end
  start=$(date +%s.%N)
  run "$@" >/dev/null
  end=$(date +%s.%N)
  printf "%.3f" "$(echo "$end - $start" | bc)"
}

median() { sort -n | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }

sanity_check
base_times=() plugin_times=() floor_times=()
for _ in $(seq "$runs"); do  # alternate so that drifts in machine load hit all sides alike
  base_times+=("$(wall "${baseline[@]}")")
  plugin_times+=("$(wall "${with_plugin[@]}")")
  if [ -n "$floor" ]; then floor_times+=("$(wall "${with_floor[@]}")"); fi
done
base=$(printf '%s\n' "${base_times[@]}" | median)
plug=$(printf '%s\n' "${plugin_times[@]}" | median)

echo "frames: $((2 * cycles)) (8 axes)"
printf 'baseline median: %.3f s  (runs: %s)\n' "$base" "${base_times[*]}"
printf 'plugin   median: %.3f s  (runs: %s)\n' "$plug" "${plugin_times[*]}"
if [ -n "$floor" ]; then
  flo=$(printf '%s\n' "${floor_times[@]}" | median)
  printf 'floor    median: %.3f s  (runs: %s)\n' "$flo" "${floor_times[*]}"
  printf 'ratio floor/baseline = %.2f (the same items with constant texts)\n' \
    "$(echo "scale=4; $flo / $base" | bc)"
  printf 'ratio plugin/floor = %.2f (what the plugin itself adds)\n' \
    "$(echo "scale=4; $plug / $flo" | bc)"
fi
ratio=$(echo "scale=4; $plug / $base" | bc)
printf 'ratio plugin/baseline = %.2f (goal <= %s)\n' "$ratio" "$goal"
if [ "$(echo "$ratio > $goal" | bc)" = 1 ]; then
  exit 1
fi
