#!/usr/bin/env bash
# The frame rate `ncservo monitor` sustains without losing a frame (docs/field.md#how-fast): a
# simulated 32-axis bus at 8 kHz without a start-up (4 frames a cycle, 32,000 frames/s; 137,600
# frames, the issue's full-speed replay) replayed by tcpreplay into one end of a veth pair at a
# given rate (`--pps`, evenly spaced), the monitor on the other end; the rate bisected between
# the bus's real-time rate and tcpreplay's full speed until the monitor's capture summary shows a loss.
# Prints each step (rate asked, rate sent, frames captured, kernel drops, the monitor's CPU time
# per frame), the highest rate with every frame captured and the load average.
#
# Usage: tests/bench/monitor_rate.sh [BUILD_DIR]     (default: the repository's build/)
# Env:   NCSERVO_BENCH_SECONDS   seconds of bus (default 4.3: 137,600 frames)
#        NCSERVO_BENCH_AXES      servo axes (default 32; 8 makes one frame a cycle, 2 copies)
#        NCSERVO_BENCH_STEPS     bisection steps (default 7)
#        NCSERVO_BENCH_REALTIME  1: tcpreplay and the monitor with a real-time policy (chrt -f),
#                                so that other jobs of a busy machine do not decide (default 0)
# Needs root (veth pair, network namespace), ip and tcpreplay. Exit status 0, 1 when a tool fails.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

seconds=${NCSERVO_BENCH_SECONDS:-4.3}
axes=${NCSERVO_BENCH_AXES:-32}
steps=${NCSERVO_BENCH_STEPS:-7}
realtime=${NCSERVO_BENCH_REALTIME:-0}

fail() { echo "monitor_rate: $*" >&2; exit 1; }
[ -x "$ncservo" ] || fail "no $ncservo (build the ncservo_cli target first)"
[ "$(id -u)" = 0 ] || fail "needs root (veth pair, network namespace)"
command -v tcpreplay >/dev/null || fail "tcpreplay is not installed"
replay_rt="" monitor_rt=""
if [ "$realtime" = 1 ]; then replay_rt="chrt -f 50" monitor_rt="chrt -f 40"; fi

work=$(mktemp -d)
ns=ncservo-rate-$$ host=nrat$$a peer=nrat$$b
trap 'ip netns del "$ns" 2>/dev/null || true; ip link del "$host" 2>/dev/null || true; rm -rf "$work"' EXIT
ip netns add "$ns"
ip link add "$host" type veth peer name "$peer" netns "$ns"
ip link set "$host" up
ip -n "$ns" link set "$peer" up

"$ncservo" simulate --no-startup --axes "$axes" --cycle-us 125 --duration "$seconds" --seed 1 \
  -o "$work/bus.pcap" 2>/dev/null || fail "simulate failed"
frames=$("$ncservo" validate --fail-on never "$work/bus.pcap" |
  sed -n 's/^.*bus.pcap: \([0-9]*\) frames.*/\1/p')
bytes=$(stat -c %s "$work/bus.pcap")
bus=$(awk -v f="$frames" -v s="$seconds" 'BEGIN { printf "%d", f / s }')  # frames/s in real time

# run PPS (0: full speed): one replay; sets sent_pps, captured, dropped, cpu_us (per frame).
run() {
  local pid ticks speed=(--pps "$1")
  [ "$1" = 0 ] && speed=(--topspeed)
  $monitor_rt "$ncservo" monitor -i "$host" --format jsonl --fail-on never >"$work/live.jsonl" \
    2>"$work/live.err" &
  pid=$!
  sleep 1
  ticks=$(awk '{ print $14 + $15 }' "/proc/$pid/stat")
  ip netns exec "$ns" $replay_rt tcpreplay --preload-pcap "${speed[@]}" -i "$peer" "$work/bus.pcap" \
    >"$work/replay.txt" 2>&1 || fail "tcpreplay: $(cat "$work/replay.txt")"
  sleep 0.5
  ticks=$(($(awk '{ print $14 + $15 }' "/proc/$pid/stat") - ticks))
  kill -INT "$pid"
  wait "$pid" || true
  sent_pps=$(sed -n 's/.*Rated: .* \([0-9.]*\) pps.*/\1/p' "$work/replay.txt" | cut -d. -f1)
  captured=$(sed -n 's/.*: \([0-9]*\) frames captured.*/\1/p' "$work/live.err")
  dropped=$(sed -n 's/.*dropped: \([0-9]*\) by the kernel, \([0-9]*\) by the interface.*/\1+\2/p' \
    "$work/live.err")
  cpu_us=$((ticks * 1000000 / $(getconf CLK_TCK) / (captured > 0 ? captured : 1)))
}

printf "%d frames of a %d-axis bus at 8 kHz (%d bytes a frame)%s; load %s\n" "$frames" "$axes" \
  $((bytes / frames)) "$([ "$realtime" = 1 ] && echo ", real-time policies")" \
  "$(cut -d' ' -f1-3 /proc/loadavg)"
report() {
  printf "%-9s sent %7d frames/s: %6d captured, dropped %s, monitor CPU %d µs a frame\n" "$1" \
    "$sent_pps" "$captured" "$dropped" "$cpu_us"
}
run 0
report "full"
full=$sent_pps
best=0
if [ "$captured" = "$frames" ]; then
  best=$full
else
  lo=$bus hi=$full
  for _ in $(seq "$steps"); do
    mid=$(((lo + hi) / 2))
    run "$mid"
    report "$mid"
    if [ "$captured" = "$frames" ]; then
      best=$sent_pps lo=$mid
    else
      hi=$mid
    fi
  done
fi
printf "sustained without loss: %d frames/s (%.1fx the bus's %d); full speed sent %d frames/s; load %s\n" \
  "$best" "$(awk -v b="$best" -v r="$bus" 'BEGIN{print b/r}')" "$bus" "$full" "$(cut -d' ' -f1-3 /proc/loadavg)"
