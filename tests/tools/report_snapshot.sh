#!/usr/bin/env bash
# Writes every report the CLI gives on the bundled, real and simulated captures into OUTDIR, so a
# refactoring can be shown to change no output: run it before and after, then `diff -r OLD NEW`.
# Usage: tests/tools/report_snapshot.sh NCSERVO OUTDIR
set -euo pipefail
ncservo=$(realpath "$1")
out=$2
src=$(cd "$(dirname "$0")/../.." && pwd)
real="$src/../shared/captures/real"
mkdir -p "$out/sim"

snapshot() {  # NAME CAPTURE [validate options...]
  local name=$1 capture=$2
  shift 2
  for format in text json jsonl junit sarif; do
    { "$ncservo" validate --fail-on never --format "$format" "$@" "$capture" 2>&1 || echo "exit $?"; } |
      sed "s#$out#OUT#g" >"$out/$name.$format"
  done
  { "$ncservo" decode --format csv "$@" "$capture" 2>&1 || echo "exit $?"; } | sed "s#$out#OUT#g" >"$out/$name.decode.csv"
}

for capture in "$src"/captures/*.pcap "$src"/captures/*.pcapng; do
  stem=$(basename "${capture%.*}")
  snapshot "bundled-$stem" "$capture"
  [ -f "$src/captures/$stem.toml" ] && snapshot "bundled-$stem-config" "$capture" --config "$src/captures/$stem.toml"
done
if [ -d "$real" ]; then
  for capture in "$real"/*.pcap* "$real"/*.cap; do
    snapshot "real-$(basename "$capture")" "$capture"
  done
fi
# Simulated: each scenario, each layout, several faults at once, lossy.
sim() {  # NAME simulate-options...
  local name=$1
  shift
  "$ncservo" simulate "$@" -o "$out/sim/$name.pcap" --layout-config "$out/sim/$name.toml" >/dev/null
  snapshot "sim-$name" "$out/sim/$name.pcap"
  snapshot "sim-$name-config" "$out/sim/$name.pcap" --config "$out/sim/$name.toml"
}
sim commissioning --scenario commissioning --axes 3 --seed 11
sim faults --scenario faults --seed 5
sim interleaved --scenario faults --layout interleaved --io-slaves 2 --axes 5 --seed 3
sim lossy --scenario commissioning --axes 6 --loss 0.02 --jitter-us 40 --seed 9 --ready-mode 1
sim nostartup --scenario soak --duration 3 --no-startup --axes 2 --seed 4
