#!/usr/bin/env bash
# The monitor's CPU with and without --metrics and --mqtt (docs/field.md#how-fast): a simulated
# 32-axis bus at 8 kHz with the faults scenario (32,000 frames/s and its findings) replayed in real
# time by tcpreplay into one end of a veth pair, the monitor on the other; each mode run in turn,
# several rounds: none; --metrics scraped once a second (as a Prometheus would, but faster than
# its default); --metrics scraped ten times a second; --mqtt to a Mosquitto broker started here;
# both. Prints, per mode, the median over the rounds of the monitor's CPU time a frame and in
# percent of the replay's wall time, and the scrape count and the formatting time of one scrape.
#
# Usage: tests/bench/monitor_telemetry_cpu.sh [BUILD_DIR]     (default: the repository's build/)
# Env:   NCSERVO_BENCH_SECONDS  seconds of bus (default 4.3, the faults scenario's least)
#        NCSERVO_BENCH_ROUNDS   rounds of every mode (default 3)
# Needs root (veth pair, network namespace), ip, tcpreplay, curl and mosquitto.
set -euo pipefail
source "$(dirname "$0")/lib.sh"

seconds=${NCSERVO_BENCH_SECONDS:-4.3}
rounds=${NCSERVO_BENCH_ROUNDS:-3}
fail() { echo "monitor_telemetry_cpu: $*" >&2; exit 1; }
[ -x "$ncservo" ] || fail "no $ncservo (build the ncservo_cli target first)"
[ "$(id -u)" = 0 ] || fail "needs root (veth pair, network namespace)"
for tool in tcpreplay curl mosquitto; do command -v $tool >/dev/null || fail "$tool is not installed"; done

work=$(mktemp -d)
ns=ncservo-tcpu-$$ host=ntcp$$a peer=ntcp$$b
broker=""
trap 'kill $broker 2>/dev/null || true; ip netns del "$ns" 2>/dev/null || true; ip link del "$host" 2>/dev/null || true; rm -rf "$work"' EXIT
ip netns add "$ns"
ip link add "$host" type veth peer name "$peer" netns "$ns"
ip link set "$host" up
ip -n "$ns" link set "$peer" up
port() { python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
mqtt_port=$(port) metrics_port=$(port)
printf 'listener %s 127.0.0.1\nallow_anonymous true\nuser root\n' "$mqtt_port" >"$work/mosquitto.conf"
mosquitto -c "$work/mosquitto.conf" >"$work/broker.log" 2>&1 &
broker=$!

"$ncservo" simulate --scenario faults --axes 32 --cycle-us 125 --duration "$seconds" --seed 1 \
  -o "$work/bus.pcap" 2>/dev/null || fail "simulate failed"
frames=$("$ncservo" validate --fail-on never "$work/bus.pcap" | sed -n 's/^.*bus.pcap: \([0-9]*\) frames.*/\1/p')
findings=$("$ncservo" validate --format jsonl --fail-on never "$work/bus.pcap" | grep -c '"rule"' || true)

# run MODE: one replay in real time; prints "CPU_US_A_FRAME CPU_PERCENT SCRAPES MS_A_SCRAPE".
run() {
  local args=() every=""
  case $1 in
  metrics-1s) args=(--metrics "127.0.0.1:$metrics_port") every=1 ;;
  metrics-100ms) args=(--metrics "127.0.0.1:$metrics_port") every=0.1 ;;
  mqtt) args=(--mqtt "mqtt://127.0.0.1:$mqtt_port/bench") ;;
  both) args=(--metrics "127.0.0.1:$metrics_port" --mqtt "mqtt://127.0.0.1:$mqtt_port/bench") every=1 ;;
  esac
  "$ncservo" monitor -i "$host" --format jsonl --fail-on never "${args[@]}" >"$work/live.jsonl" 2>"$work/live.err" &
  local pid=$! scraper="" ticks start ms
  sleep 1
  if [ -n "$every" ]; then
    while :; do curl -sf "http://127.0.0.1:$metrics_port/metrics" >/dev/null || true; sleep "$every"; done &
    scraper=$!
  fi
  ticks=$(awk '{ print $14 + $15 }' "/proc/$pid/stat")
  start=$(date +%s%N)
  ip netns exec "$ns" tcpreplay --preload-pcap -q -i "$peer" "$work/bus.pcap" >"$work/replay.txt" 2>&1 ||
    fail "tcpreplay: $(cat "$work/replay.txt")"
  sleep 0.3
  ms=$((($(date +%s%N) - start) / 1000000))
  ticks=$(($(awk '{ print $14 + $15 }' "/proc/$pid/stat") - ticks))
  [ -z "$scraper" ] || kill "$scraper"
  kill -INT "$pid"
  wait "$pid" || true
  grep -q "$frames frames captured; dropped: 0 by the kernel" "$work/live.err" ||
    echo "  ($1: $(grep -o '[0-9]* frames captured; dropped: [0-9]* by the kernel' "$work/live.err"))" >&2
  local scrapes
  scrapes=$(sed -n 's/.*--metrics: \([0-9]*\) scrapes, \([0-9.]*\) ms formatting each.*/\1 \2/p' "$work/live.err")
  awk -v t="$ticks" -v hz="$(getconf CLK_TCK)" -v f="$frames" -v ms="$ms" -v s="${scrapes:-- -}" \
    'BEGIN { printf "%.2f %.1f %s\n", t / hz * 1e6 / f, t / hz * 100000 / ms, s }'
}

printf "%d frames of a 32-axis bus at 8 kHz with %d findings, in real time; %d rounds; load %s\n" \
  "$frames" "$findings" "$rounds" "$(cut -d' ' -f1-3 /proc/loadavg)"
modes=(none metrics-1s metrics-100ms mqtt both)
declare -A results
for r in $(seq "$rounds"); do
  for mode in "${modes[@]}"; do results[$mode]+="$(run "$mode")"$'\n'; done
done
for mode in "${modes[@]}"; do
  printf '%s' "${results[$mode]}" | sort -n | awk -v m="$mode" -v n="$rounds" \
    'NR == int((n + 1) / 2) { printf "%-14s %6.2f µs a frame, %5.1f %% of a CPU; %s scrapes, %s ms each\n", m, $1, $2, $3, $4 }'
done
