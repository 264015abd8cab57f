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

cpu_seconds() { # FILE: CPU seconds (user + system) of the children line `times` wrote to FILE
  tail -n 1 "$1" |
    awk '{ t = 0; for (i = 1; i <= 2; ++i) { split($i, p, /[ms]/); t += 60 * p[1] + p[2] } print t }'
}

# measure SIDE ARGS...: one run; appends its wall and CPU seconds to SIDE_wall and SIDE_cpu.
# CPU time is printed too: on a shared machine it is the steadier of the two.
measure() {
  local -n walls=$1_wall cpus=$1_cpu
  shift
  local start end
  times >"$tmp/times.before"  # not in a subshell: a subshell's children are not this shell's
  start=$(date +%s.%N)
  run "$@" >/dev/null
  end=$(date +%s.%N)
  times >"$tmp/times.after"
  walls+=("$(printf "%.3f" "$(echo "$end - $start" | bc)")")
  cpus+=("$(printf "%.3f" \
    "$(echo "$(cpu_seconds "$tmp/times.after") - $(cpu_seconds "$tmp/times.before")" | bc)")")
}

median() { printf '%s\n' "$@" | sort -n | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }
ratio() { echo "scale=4; $1 / $2" | bc; }

sanity_check
base_wall=() base_cpu=() plugin_wall=() plugin_cpu=() floor_wall=() floor_cpu=()
for _ in $(seq "$runs"); do  # alternate so that drifts in machine load hit all sides alike
  measure base "${baseline[@]}"
  measure plugin "${with_plugin[@]}"
  if [ -n "$floor" ]; then measure floor "${with_floor[@]}"; fi
done
base=$(median "${base_wall[@]}") base_c=$(median "${base_cpu[@]}")
plug=$(median "${plugin_wall[@]}") plug_c=$(median "${plugin_cpu[@]}")

echo "frames: $((2 * cycles)) (8 axes), $runs runs each; medians of wall / CPU seconds"
printf 'baseline: %.3f s / %.3f s  (wall: %s)\n' "$base" "$base_c" "${base_wall[*]}"
printf 'plugin:   %.3f s / %.3f s  (wall: %s)\n' "$plug" "$plug_c" "${plugin_wall[*]}"
if [ -n "$floor" ]; then
  flo=$(median "${floor_wall[@]}") flo_c=$(median "${floor_cpu[@]}")
  printf 'floor:    %.3f s / %.3f s  (wall: %s)\n' "$flo" "$flo_c" "${floor_wall[*]}"
  printf 'ratio floor/baseline = %.2f wall, %.2f CPU (the same items with constant texts)\n' \
    "$(ratio "$flo" "$base")" "$(ratio "$flo_c" "$base_c")"
  printf 'ratio plugin/floor = %.2f wall, %.2f CPU (what the plugin itself adds)\n' \
    "$(ratio "$plug" "$flo")" "$(ratio "$plug_c" "$flo_c")"
fi
wall_ratio=$(ratio "$plug" "$base")
printf 'ratio plugin/baseline = %.2f wall (goal <= %s), %.2f CPU\n' "$wall_ratio" "$goal" \
  "$(ratio "$plug_c" "$base_c")"
if [ "$(echo "$wall_ratio > $goal" | bc)" = 1 ]; then
  exit 1
fi
