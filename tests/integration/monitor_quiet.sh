#!/usr/bin/env bash
# monitor_quiet.sh SRC BUILD: `ncservo monitor` on a link with no traffic at all (one end of a
# veth pair whose other end is silent, in a network namespace of its own) ends on time:
# `--duration 3` exits within 3-4 s, and Ctrl-C within a second, each with the usual report (no
# servo was seen: exit 4, the NO SERVO verdict); and it waits rather than spins, with --metrics
# too: under a tenth of a CPU-second over a quiet second. Needs root (veth, namespaces): otherwise exit 77
# with the reason (under CI: fails).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

[ "$(id -u)" = 0 ] || skip "needs root (veth pair, network namespace)"
require_program ip

veth_pair ncsq
cd "$WORK"

# --duration on a quiet link: the run ends by itself; `timeout` only guards the test.
start=$(date +%s%N)
rc=0
timeout 20 "$NCSERVO" monitor -i "$host" --duration 3 >out.txt 2>err.txt || rc=$?
ms=$((($(date +%s%N) - start) / 1000000))
[ "$rc" != 124 ] || fail "--duration 3 on a quiet link: still running after 20 s"
[ "$rc" = 4 ] || fail "--duration 3: exit $rc, expected 4 (no servo): $(cat err.txt)"
[ "$ms" -ge 3000 ] && [ "$ms" -lt 4000 ] || fail "--duration 3 took $ms ms, expected 3000-3999"
grep -q "0 frames captured" err.txt || fail "no capture summary: $(cat err.txt)"
grep -q "NO SERVO" out.txt || fail "no report: $(cat out.txt)"
echo "ok --duration 3 on a quiet link: exit $rc after $ms ms"

# Ctrl-C on a quiet link, a second in: the report follows at once.
"$NCSERVO" monitor -i "$host" >out.txt 2>err.txt &
pid=$!
sleep 1
start=$(date +%s%N)
kill -INT "$pid"
rc=0
for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
kill -0 "$pid" 2>/dev/null && { kill -KILL "$pid"; fail "Ctrl-C on a quiet link: still running after 5 s"; }
wait "$pid" || rc=$?
ms=$((($(date +%s%N) - start) / 1000000))
[ "$rc" = 4 ] || fail "Ctrl-C: exit $rc, expected 4 (no servo): $(cat err.txt)"
[ "$ms" -lt 1000 ] || fail "Ctrl-C took $ms ms to end the run"
grep -q "NO SERVO" out.txt || fail "no report after Ctrl-C: $(cat out.txt)"
echo "ok Ctrl-C on a quiet link: exit $rc after $ms ms"

# A quiet monitor waits for frames; it does not poll in a loop (once it did, with no --metrics,
# a whole CPU).
hz=$(getconf CLK_TCK)
for options in "" "--metrics 127.0.0.1:0"; do
  # shellcheck disable=SC2086
  "$NCSERVO" monitor -i "$host" $options >out.txt 2>err.txt &
  pid=$!
  sleep 0.5
  ticks=$(awk '{ print $14 + $15 }' "/proc/$pid/stat")
  sleep 1
  ticks=$(($(awk '{ print $14 + $15 }' "/proc/$pid/stat") - ticks))
  kill -INT "$pid"
  wait "$pid" || true
  [ $((ticks * 10)) -lt "$hz" ] ||
    fail "monitor ${options:-without options} on a quiet link: $((ticks * 1000 / hz)) ms of CPU in a second"
  echo "ok a quiet second ${options:+with $options }took $((ticks * 1000 / hz)) ms of CPU"
done
echo PASS
