#!/usr/bin/env bash
# simulate_soak.sh SRC BUILD [SECONDS]
# A clean simulation of one hour at 1 kHz with 8 axes, piped through `ncservo validate -`: no
# error or warning, every frame read, and both processes in constant memory (the same peak RSS,
# under 32 MiB, for a 60 s run and for the long one); the hour's frames and memory are what
# captures/README.md says they are (its time depends on the machine and is not judged).
SRC=$1 BUILD=$2 SECONDS_LONG=${3:-3600}
source "$SRC/tests/integration/lib.sh"
# A sanitizer build keeps freed memory in quarantine (ASan: up to 256 MiB), so its RSS says
# nothing about the program's own: there only the verdicts are checked, and ten minutes run the
# same code as the hour at a sixth of the cost.
sanitized=false
if grep -q '^NCSERVO_SANITIZE:BOOL=ON' "$BUILD/CMakeCache.txt" 2>/dev/null; then
  sanitized=true
  [ "$SECONDS_LONG" -le 600 ] || SECONDS_LONG=600
fi
run() { # run SECONDS: the report in $WORK/report-SECONDS.txt, peak RSS (KiB) of each in $WORK/rss-*
  local seconds=$1
  set +e
  /usr/bin/time -f %M -o "$WORK/rss-sim-$seconds" "$NCSERVO" simulate --scenario soak --axes 8 \
    --duration "$seconds" -o - 2>"$WORK/sim.err" |
    /usr/bin/time -f %M -o "$WORK/rss-val-$seconds" "$NCSERVO" validate --fail-on warning - \
      >"$WORK/report-$seconds.txt"
  local status=("${PIPESTATUS[@]}")
  set -e
  [ "${status[0]}" = 0 ] || fail "simulate $seconds s exit ${status[0]}: $(cat "$WORK/sim.err")"
  [ "${status[1]}" = 0 ] || fail "validate of $seconds s exit ${status[1]}: $(grep -v '^    ' "$WORK/report-$seconds.txt" | head)"
  grep -q "^verdict: PASS - 0 errors, 0 warnings, 0 info" "$WORK/report-$seconds.txt" ||
    fail "$seconds s: $(tail -1 "$WORK/report-$seconds.txt")"
  local frames
  frames=$(grep -o '^-: [0-9]* frames' "$WORK/report-$seconds.txt" | grep -o '[0-9]*')
  # start-up frames plus two frames (master's and returned copy) per 1 ms cycle
  [ "$frames" -ge $((seconds * 2000 - 100)) ] || fail "$seconds s: only $frames frames validated"
}
run 60
run "$SECONDS_LONG"
if $sanitized; then
  echo "simulate_soak: sanitizer build: peak RSS not judged ($(tail -1 "$WORK/rss-sim-$SECONDS_LONG") KiB simulate, $(tail -1 "$WORK/rss-val-$SECONDS_LONG") KiB validate)"
  echo "simulate_soak: $SECONDS_LONG s at 1 kHz, 8 axes: PASS with no error or warning"
  exit 0
fi
for who in sim val; do
  short=$(tail -1 "$WORK/rss-$who-60") long=$(tail -1 "$WORK/rss-$who-$SECONDS_LONG")
  [ "$long" -lt 32768 ] || fail "$who: peak RSS $long KiB for $SECONDS_LONG s (limit 32 MiB)"
  [ "$long" -lt $((short + 2048)) ] || fail "$who: peak RSS grew from $short KiB (60 s) to $long KiB"
  echo "simulate_soak: $who peak RSS $short KiB for 60 s, $long KiB for $SECONDS_LONG s"
done
if [ "$SECONDS_LONG" = 3600 ]; then
  python3 - "$SRC/captures/README.md" "$WORK/report-3600.txt" "$WORK/rss-sim-3600" "$WORK/rss-val-3600" <<'PY' ||
import re, sys
said = re.search(r"measured: ([\d.]+) million frames in about \d+ s[^,]*,\s+about (\d+) MiB peak",
                 open(sys.argv[1]).read().replace("\n", " "))
assert said, "captures/README.md quotes no soak measurement"
frames = int(re.search(r"^-: (\d+) frames", open(sys.argv[2]).read(), re.M)[1])
assert f"{frames / 1e6:.1f}" == said[1], f"{frames} frames, the README says {said[1]} million"
for rss in sys.argv[3:]:
    mib = int(open(rss).read().split()[-1]) / 1024
    assert abs(mib - int(said[2])) <= 2, f"peak {mib:.1f} MiB, the README says about {said[2]} MiB"
PY
    fail "captures/README.md's soak numbers are not this run's"
fi
echo "simulate_soak: $SECONDS_LONG s at 1 kHz, 8 axes: PASS with no error or warning, constant memory"
