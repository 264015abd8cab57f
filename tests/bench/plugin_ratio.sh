#!/usr/bin/env bash
# What the ncservo plugin costs where Wireshark users feel it, in CPU time, on one simulated
# 8-axis capture, every side in turn run by run:
#   opening    `tshark -r` (the packet list, tree not built)     with / without the plugin
#   filtering  `-Y 'ncservo.scw.se == 2'` with the plugin         / `-Y 'ecat.cmd == 12'` without
#   fields     `-T fields -e ncservo.…` with the plugin           / the same with the item floor
# The item floor (BUILD_DIR/plugin/ncservo_item_floor.so, built here from tests/bench/) is the
# plugin's dissector with constant texts: the same first pass and items, so what Wireshark itself
# spends on them.
# Usage: tests/bench/plugin_ratio.sh [BUILD_DIR]          (default: build)
# Env:   NCSERVO_BENCH_CYCLES  cycles in the capture (default 25000 = 50,000 frames)
#        NCSERVO_BENCH_RUNS    runs of each side; the median counts (default 7)
#        NCSERVO_BENCH_GOALS   "OPEN FILTER FIELDS" highest ratios (default "1.10 1.20 1.10")
# Exit 1 when a ratio is above its goal, 2 when a run fails.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

cycles=${NCSERVO_BENCH_CYCLES:-25000}
runs=${NCSERVO_BENCH_RUNS:-7}
read -r goal_open goal_filter goal_fields <<<"${NCSERVO_BENCH_GOALS:-1.10 1.20 1.10}"
runner=$root/tests/tools/tshark-with-plugin.sh
plugin=$(realpath "$build/plugin/ncservo.so" 2>/dev/null || true)
if [ -z "$plugin" ] || [ ! -f "$plugin" ]; then
  echo "plugin_ratio: no $build/plugin/ncservo.so (build first)" >&2
  exit 2
fi
if ! cmake --build "$build" --target ncservo_item_floor >&2; then
  echo "plugin_ratio: cannot build the item floor plugin in $build" >&2
  exit 2
fi
floor=$(realpath "$build/plugin/ncservo_item_floor.so")

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# as root the runner drops to user nobody, which must be able to read the capture
chmod a+rx "$tmp"
cap=$tmp/bench.pcap
python3 "$root/tests/tools/gen_capture.py" --axes 8 --cycles "$cycles" -o "$cap"
chmod a+r "$cap"

ncservo_fields=(-T fields -e ncservo.ssp -e ncservo.scw -e ncservo.ext_code -e ncservo.actpos
                -e ncservo.ssw -e ncservo.sew -e ncservo.msg_code -e ncservo.msg_data)
# side name, then the runner's arguments
declare -A side_args=(
  [open_base]="none -r $cap"
  [open_plugin]="$plugin -r $cap"
  [filter_base]="none -r $cap -Y ecat.cmd==12"
  [filter_plugin]="$plugin -r $cap -Y ncservo.scw.se==2"
  [fields_floor]="$floor -r $cap ${ncservo_fields[*]}"
  [fields_plugin]="$plugin -r $cap ${ncservo_fields[*]}"
)
sides=(open_base open_plugin filter_base filter_plugin fields_floor fields_plugin)

run() { # run ARGS... > OUT: the runner, failing loudly with tshark's messages
  if ! "$runner" "$@" 2>"$tmp/stderr"; then
    echo "plugin_ratio: tshark-with-plugin.sh $* failed:" >&2
    cat "$tmp/stderr" >&2
    exit 2
  fi
}

# The plugin must decode what it is timed on: the filter must select frames, and the fields
# must come out, or a fast run would prove nothing.
sanity_check() {
  local selected with_fields
  # shellcheck disable=SC2086
  selected=$(run ${side_args[filter_plugin]} -2 -c 2000 | wc -l)
  # shellcheck disable=SC2086
  with_fields=$(run ${side_args[fields_plugin]} -2 -c 2000 | awk -F'\t' '$5 != ""' | wc -l)
  if [ "$selected" -lt 1 ] || [ "$with_fields" -lt 5 ]; then
    echo "plugin_ratio: the plugin decoded too little ($selected frames with SE 2 in the" \
      "first 2000, $with_fields of them with inputs)" >&2
    exit 2
  fi
}

cpu_seconds() { # FILE: CPU seconds (user + system) of the children line `times` wrote to FILE
  tail -n 1 "$1" |
    awk '{ t = 0; for (i = 1; i <= 2; ++i) { split($i, p, /[ms]/); t += 60 * p[1] + p[2] } print t }'
}

declare -A cpu=()  # side -> space-separated CPU seconds of its runs
measure() { # SIDE
  times >"$tmp/times.before"  # not in a subshell: a subshell's children are not this shell's
  # shellcheck disable=SC2086
  run ${side_args[$1]} >/dev/null
  times >"$tmp/times.after"
  cpu[$1]+="$(echo "$(cpu_seconds "$tmp/times.after") - $(cpu_seconds "$tmp/times.before")" | bc) "
}

median() { printf '%s\n' $1 | sort -n | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }

sanity_check
for _ in $(seq "$runs"); do  # in turn, so that drifts in machine load hit all sides alike
  for side in "${sides[@]}"; do measure "$side"; done
done

echo "frames: $((2 * cycles)) (8 axes), $runs runs each; CPU seconds (user + system), medians"
for side in "${sides[@]}"; do
  printf '  %-14s %7.3f s  (runs: %s)\n' "$side" "$(median "${cpu[$side]}")" "${cpu[$side]% }"
done
status=0
report() { # NAME NUMERATOR DENOMINATOR GOAL
  local r
  r=$(echo "scale=4; $(median "${cpu[$2]}") / $(median "${cpu[$3]}")" | bc)
  local verdict=met
  if [ "$(echo "$r > $4" | bc)" = 1 ]; then verdict="NOT met" status=1; fi
  printf 'ratio %-10s %s/%s = %.3f (goal <= %s: %s)\n' "$1" "$2" "$3" "$r" "$4" "$verdict"
}
report opening open_plugin open_base "$goal_open"
report filtering filter_plugin filter_base "$goal_filter"
report fields fields_plugin fields_floor "$goal_fields"
exit "$status"
