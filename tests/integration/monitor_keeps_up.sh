#!/usr/bin/env bash
# monitor_keeps_up.sh SRC BUILD: `ncservo monitor` keeps up with a busy bus with room to spare
# (docs/field.md#how-fast): 3 s of a simulated 32-axis bus at 8 kHz (32,000 frames/s) replayed by
# tcpreplay at four times real time into one end of a veth pair, the monitor on the other: every
# frame sent is captured (the capture summary on standard error and the report's frame count) and
# the kernel dropped none. Needs root (veth, namespaces) and tcpreplay: otherwise exit 77 with the
# reason (under CI: fails). A machine too busy to test it is skipped, saying so (77, even under
# CI: nothing is missing): tcpreplay that cannot send at 4x (the frames it sent must all be captured
# all the same), or a monitor that lost frames after waiting for a CPU 100 ms or more of the replay
# (the kernel's ring holds 150 ms of it) or while a hypervisor took 50 ms or more of the CPUs;
# each tried three times, the monitor then with a real-time policy as docs/field.md advises on a
# busy PC. Frames lost by a monitor that waited less are tried again too, as a user starts it: a
# shared machine slows a process in ways its counters do not show (CI's monitor once needed 77 %
# of a CPU for the replay, with 5 ms of waiting and 10 ms stolen, where it needs 25-38 % on an idle
# one), and a monitor that cannot keep up loses frames every time (the build before the ring
# change lost 25,940 of 95,970). The test fails when no attempt captured every frame and one of
# them lost frames without waiting.
# With --telemetry (monitor_keeps_up.telemetry) the monitor also serves --metrics, scraped ten
# times a second during the replay, and publishes --mqtt to a Mosquitto broker started here: the
# same claim holds with both on (docs/field.md#how-fast gives the CPU of both runs). Replayed in
# bursts at 4x, the bus looks broken to the rules: 12,000 to 26,000 findings in 0.75 s, more than
# a loaded 2-core machine's broker takes in as they come (CI's dropped 1,480 from a queue of
# 10,000), so the queue here holds them all, and every one must be acknowledged by the end.
SRC=$1 BUILD=$2 MODE=${3:-}
source "$SRC/tests/integration/lib.sh"

[ "$(id -u)" = 0 ] || skip "needs root (veth pair, network namespace)"
require_program tcpreplay ip
telemetry=()
if [ "$MODE" = --telemetry ]; then
  require_program mosquitto curl
fi

veth_pair ncsk
cd "$WORK"
if [ "$MODE" = --telemetry ]; then
  mqtt_port=$(free_port) metrics_port=$(free_port)
  printf 'listener %s 127.0.0.1\nallow_anonymous true\nuser root\n' "$mqtt_port" >mosquitto.conf
  mosquitto -c mosquitto.conf >broker.log 2>&1 &
  broker=$!
  trap 'kill "$broker" 2>/dev/null || true; ip netns del "$ns" 2>/dev/null || true; ip link del "$host" 2>/dev/null || true; rm -rf "$WORK"' EXIT
  telemetry=(--metrics "127.0.0.1:$metrics_port" --mqtt "mqtt://127.0.0.1:$mqtt_port/keeps-up"
    --mqtt-queue 100000)
fi
seconds=3
"$NCSERVO" simulate --axes 32 --cycle-us 125 --duration "$seconds" -o bus.pcap 2>/dev/null
frames=$("$NCSERVO" validate --fail-on never bus.pcap | sed -n 's/^bus.pcap: \([0-9]*\) frames.*/\1/p')
[ "$frames" -gt $((seconds * 31000)) ] || fail "the simulated bus has $frames frames in $seconds s"

# Four times the bus's frame rate, sent 8 frames at a time: timing every frame (--multiplier 4),
# tcpreplay reaches only ~3.5x here, however idle the machine, while 8-frame bursts hold the rate
# and are harder on the monitor than an even stream. It runs under a real-time policy so that a
# busy machine does not slow it; the replay is shorter than the kernel's real-time
# throttling period (950 ms of each second), which would stop it. The monitor runs as a user
# starts it, and with a real-time policy below tcpreplay's once the machine proved too busy.
realtime="chrt -f 50" monitor_realtime=""
$realtime true 2>/dev/null || { realtime=""; echo "note: no real-time policy allowed; replaying without"; }

# cpu_ns PID, waited_ns PID: the time the process has run, and waited on a run queue for a CPU
# (/proc/PID/schedstat). stolen_ms: the time a hypervisor ran something else while this machine's
# CPUs wanted to run (/proc/stat "steal", all CPUs); the process's own counts do not show it.
cpu_ns() { awk '{ print $1 }' "/proc/$1/schedstat"; }
waited_ns() { awk '{ print $2 }' "/proc/$1/schedstat"; }
stolen_ms() { awk -v hz="$(getconf CLK_TCK)" '/^cpu / { printf "%d\n", $9 * 1000 / hz }' /proc/stat; }

# replay: the monitor listening, the capture replayed at 4x, then Ctrl-C. Sets sent, sent_s,
# busy_pct (the monitor's CPU time over the replay's wall time), waited_ms (its wait for a CPU
# meanwhile) and the monitor's output.
replay() {
  $monitor_realtime "$NCSERVO" monitor -i "$host" --fail-on never "${telemetry[@]}" >live.txt 2>live.err &
  local pid=$!
  sleep 1
  local scraper=""
  if [ ${#telemetry[@]} -gt 0 ]; then
    while :; do curl -sf "http://127.0.0.1:$metrics_port/metrics" >/dev/null; sleep 0.1; done &
    scraper=$!
  fi
  local ran waited start replay_ms stolen
  ran=$(cpu_ns "$pid")
  waited=$(waited_ns "$pid")
  stolen=$(stolen_ms)
  start=$(date +%s%N)
  ip netns exec "$ns" $realtime tcpreplay --preload-pcap --pps $((frames * 4 / seconds)) \
    --pps-multi 8 -i "$peer" bus.pcap >replay.txt 2>&1 || fail "tcpreplay: $(cat replay.txt)"
  replay_ms=$((($(date +%s%N) - start) / 1000000))
  busy_pct=$((($(cpu_ns "$pid") - ran) / 10000 / replay_ms))
  waited_ms=$((($(waited_ns "$pid") - waited) / 1000000))
  stolen_ms=$(($(stolen_ms) - stolen))
  [ -z "$scraper" ] || kill "$scraper"
  sleep 0.5  # the kernel hands the last block over within 100 ms
  kill -INT "$pid"
  wait "$pid" || fail "monitor: exit $?: $(cat live.err)"
  sent=$(sed -n 's/.*Actual: \([0-9]*\) packets.*/\1/p' replay.txt)
  sent_s=$(sed -n 's/.*sent in \([0-9.]*\) seconds.*/\1/p' replay.txt)
  [ "$sent" = "$frames" ] || fail "tcpreplay sent $sent of $frames frames: $(cat replay.txt)"
}

busy="" lost=""
for attempt in 1 2 3; do
  replay
  summary=$(grep "frames captured" live.err) || fail "no capture summary: $(cat live.err)"
  rate=$(awk -v f="$frames" -v s="$sent_s" -v d="$seconds" 'BEGIN { printf "%d frames/s, %.2fx real time", f / s, d / s }')
  if [[ "$summary" != *": $frames frames captured; dropped: 0 by the kernel, 0 by the interface" ]]; then
    if [ "$waited_ms" -lt 100 ] && [ "$stolen_ms" -lt 50 ]; then
      lost="the monitor lost frames at $rate, having waited $waited_ms ms for a CPU, $stolen_ms ms stolen by the hypervisor (CPU $busy_pct % of the replay): $summary"
      echo "attempt $attempt${monitor_realtime:+ ($monitor_realtime)}: $lost"
      continue
    fi
    busy="the monitor waited $waited_ms ms for a CPU and the hypervisor took $stolen_ms ms of the CPUs during the replay, and frames were lost: $summary"
    echo "attempt $attempt${monitor_realtime:+ ($monitor_realtime)}: $busy"
    [ -z "$realtime" ] || monitor_realtime="chrt -f 40"
    continue
  fi
  grep -q "^$host: $frames frames," live.txt || fail "the report's frame count: $(grep -m1 frames live.txt)"
  if [ ${#telemetry[@]} -gt 0 ]; then
    scrapes=$(grep -o -- "--metrics: [0-9]* scrapes, [0-9.]* ms formatting each" live.err) ||
      fail "no scrape: $(cat live.err)"
    grep -q "connected to" live.err || fail "--mqtt never connected: $(cat live.err)"
    ! grep -q "messages not acknowledged\|messages dropped" live.err || fail "--mqtt: $(cat live.err)"
  fi
  # 4x of 3 s is 0.75 s: tcpreplay that took over 0.825 s did not replay at 4x.
  if awk -v s="$sent_s" -v d="$seconds" 'BEGIN { exit !(s > d / 4 * 1.1) }'; then
    busy="tcpreplay sent at $rate only (every frame was captured)"
    echo "attempt $attempt${monitor_realtime:+ ($monitor_realtime)}: $busy"
    continue
  fi
  busy="" lost=""
  break
done
[ -z "$lost" ] || fail "no attempt captured every frame; the last to lose frames without waiting: $lost"
[ -z "$busy" ] || { echo "SKIPPED: the machine is too busy to test it: $busy"; exit 77; }
echo "ok $frames frames at $rate: all captured, none dropped (${monitor_realtime:+the monitor under $monitor_realtime; }monitor CPU $busy_pct % of the replay, $waited_ms ms waiting for one)${scrapes:+; $scrapes}"
echo PASS
