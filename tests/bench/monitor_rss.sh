#!/usr/bin/env bash
# How much memory `ncservo monitor` holds over a long run: a 4 kHz 8-axis bus (a simulated 10 s
# soak without a start-up, 8,000 frames/s) replayed in a loop by tcpreplay into one end of a veth
# pair while the monitor listens on the other, its VmRSS (/proc/PID/status) sampled every
# NCSERVO_BENCH_INTERVAL seconds. Prints each sample, the peak (VmHWM, which counts the kernel's
# capture ring mapped into the process) and the growth from a tenth of the run to its end.
# Goals: peak RSS under 32 MiB; growth over the last nine tenths (9 minutes of 10) under 1 MiB.
#
# Usage: tests/bench/monitor_rss.sh [BUILD_DIR]     (default: the repository's build/)
# Env:   NCSERVO_BENCH_DURATION  seconds of the run (default 600), a multiple of 10
#        NCSERVO_BENCH_INTERVAL  seconds between samples (default 10)
# Needs root (veth pair, network namespace), ip and tcpreplay. The replay keeps the capture's
# timing, under a real-time policy (not `--pps`, which sends in bursts: a 5 µs cycle with gaps, a
# storm of COM findings); where it still falls behind, the run is longer than the duration (the
# time it took is printed) and the findings say where it stalled.
# The goals are reported PASS or MISS; the exit status is 0 whatever they are, 1 when a tool fails.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

duration=${NCSERVO_BENCH_DURATION:-600}
interval=${NCSERVO_BENCH_INTERVAL:-10}
goal_peak_kib=$((32 * 1024)) goal_growth_kib=1024

fail() { echo "monitor_rss: $*" >&2; exit 1; }
[ -x "$ncservo" ] || fail "no $ncservo (build the ncservo_cli target first)"
[ "$(id -u)" = 0 ] || fail "needs root (veth pair, network namespace)"
command -v tcpreplay >/dev/null || fail "tcpreplay is not installed"
[ $((duration % 10)) = 0 ] && [ "$duration" -ge 10 ] || fail "NCSERVO_BENCH_DURATION: a multiple of 10"

work=$(mktemp -d)
ns=ncservo-rss-$$ host=nrss$$a peer=nrss$$b
cleanup() {
  rm -rf "$work"
  if [ -n "${monitor:-}" ]; then kill "$monitor" 2>/dev/null || true; fi
  if [ -n "${replay:-}" ]; then kill "$replay" 2>/dev/null || true; fi
  ip netns del "$ns" 2>/dev/null || true
  ip link del "$host" 2>/dev/null || true
}
trap cleanup EXIT
ip netns add "$ns"
ip link add "$host" type veth peer name "$peer" netns "$ns"
ip link set "$host" up
ip -n "$ns" link set "$peer" up

"$ncservo" simulate --scenario soak --no-startup --axes 8 --cycle-us 250 --duration 10 --seed 1 \
  -o "$work/bus.pcap" 2>/dev/null || fail "simulate failed"
frames=$("$ncservo" validate --fail-on never "$work/bus.pcap" |
  sed -n 's/^[^:]*: \([0-9]*\) frames.*/\1/p' | head -1)
loops=$((duration / 10))

# A real-time policy keeps the replay on time on a busy machine: it sleeps (--timer=nano) with no
# timer slack and wakes first (monitor_live.sh).
realtime="chrt -f 50"
$realtime true 2>/dev/null || realtime=""
"$ncservo" monitor -i "$host" --format jsonl --fail-on never >"$work/live.jsonl" 2>"$work/live.err" &
monitor=$!
sleep 1
ip netns exec "$ns" $realtime tcpreplay -q --preload-pcap --timer=nano --loop "$loops" -i "$peer" \
  "$work/bus.pcap" >"$work/replay.txt" 2>&1 &
replay=$!

printf "monitor on a veth pair, %s loops of %s frames (10 s of a 4 kHz 8-axis bus) (load %s)\n" \
  "$loops" "$frames" "$(cut -d' ' -f1-3 /proc/loadavg)"
kib() { sed -n "s/^$1:[[:space:]]*\([0-9]*\) kB/\1/p" "/proc/$monitor/status"; }
start=$(date +%s)
samples=()
while kill -0 "$replay" 2>/dev/null; do
  sleep "$interval"
  kill -0 "$monitor" 2>/dev/null || fail "the monitor ended early: $(cat "$work/live.err")"
  rss=$(kib VmRSS)
  samples+=("$(($(date +%s) - start)) $rss")
  printf "%4d s  VmRSS %6d KiB\n" $(($(date +%s) - start)) "$rss"
done
peak=$(kib VmHWM)
wait "$replay" || fail "tcpreplay failed: $(cat "$work/replay.txt")"
replay=""
sleep 1
kill -INT "$monitor"
wait "$monitor" || true
monitor=""
sent=$(sed -n 's/.*Actual: \([0-9]*\) packets.*/\1/p' "$work/replay.txt")
grep "frames captured" "$work/live.err" | sed 's/^ncservo monitor: //'
echo "tcpreplay sent $sent frames: $(grep -o 'sent in [0-9.]* seconds' "$work/replay.txt")"
echo "findings: $(grep -c '"rule"' "$work/live.jsonl" || true), incidents: $(grep -c '"incident"' "$work/live.jsonl" || true) (load $(cut -d' ' -f1-3 /proc/loadavg))"

# The growth from the first sample at or after a tenth of the run to the last sample.
tenth=$((duration / 10))
from=""
for s in "${samples[@]}"; do
  read -r t r <<<"$s"
  [ -z "$from" ] && [ "$t" -ge "$tenth" ] && from=$r from_t=$t
done
[ -n "$from" ] || fail "no sample after ${tenth} s"
read -r last_t last <<<"${samples[-1]}"
growth=$((last - from))
goal() { [ "$1" = 1 ] && echo PASS || echo MISS; }
printf "peak RSS %d KiB (%.1f MiB): under 32 MiB: %s\n" "$peak" \
  "$(awk -v k="$peak" 'BEGIN{print k/1024}')" "$(goal $((peak < goal_peak_kib ? 1 : 0)))"
printf "growth %+d KiB from %d s to %d s: under 1 MiB: %s\n" "$growth" "$from_t" "$last_t" \
  "$(goal $((growth < goal_growth_kib ? 1 : 0)))"
