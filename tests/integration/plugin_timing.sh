#!/usr/bin/env bash
# plugin_timing.sh SRC BUILD
# Timing in Wireshark against `ncservo validate` on the same capture, timed by
# the capture's own timestamps as the plugin times it:
# - `tshark -q -z ncservo,timing`, in one pass and in two, prints exactly validate's text block;
# - the per-frame fields ncservo.cycle.interval and ncservo.latency hold every sample of the
#   JSON report's timing: the same count, median and max;
# - they are numbers to the I/O statistics: `-z io,stat` gives their mean and max over the
#   capture as the JSON report does.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

run_tshark() { # OUT CAPTURE tshark-args...
  local out=$1 capture=$2
  shift 2
  "$TSHARK" "$PLUGIN" -r "$capture" "$@" >"$out" 2>"$WORK/tshark.err" ||
    fail "tshark $* on $capture exited $?: $(cat "$WORK/tshark.err")"
  [ ! -s "$WORK/tshark.err" ] || fail "tshark $* printed on stderr: $(head -3 "$WORK/tshark.err")"
}

# The text block: its first line and those of the same block after it.
timing_block() {
  awk '/^timing \(/ {on = 1; print; next} on && /^  / {print; next} {on = 0}' "$1"
}

# One row per capture: NAME, then how it is made (a bundled file, or simulate's options).
cases=(
  "bundled-sim-faults|$SRC/captures/sim-faults-4axis.pcap"
  "bundled-commissioning|$SRC/captures/commissioning-4axis.pcap"
  "jitter-latency-pcap|--no-startup --axes 2 --duration 2 --jitter-us 30 --latency-us 80 --seed 3 -o jitter.pcap"
  "late-lost-pcapng|--axes 3 --duration 2 --latency-us 150 --late-cycle 0.9:400 --lost-cycles 1.5:2 --seed 8 -o late.pcapng"
)
for row in "${cases[@]}"; do
  name=${row%%|*}
  how=${row#*|}
  if [ -f "$how" ]; then
    cap=$how
  else
    read -r -a options <<<"$how"
    (cd "$WORK" && "$NCSERVO" simulate "${options[@]}" >/dev/null 2>&1) || fail "$name: simulate $how"
    cap="$WORK/${options[-1]}"
  fi
  "$NCSERVO" validate --timestamps capture --fail-on never "$cap" >"$WORK/$name.txt" ||
    fail "$name: validate exited $?"
  "$NCSERVO" validate --timestamps capture --fail-on never --format json "$cap" >"$WORK/$name.json" ||
    fail "$name: validate --format json exited $?"
  timing_block "$WORK/$name.txt" >"$WORK/$name.cli"
  [ -s "$WORK/$name.cli" ] || fail "$name: validate printed no timing block"
  grep -q ' cycle min ' "$WORK/$name.cli" || fail "$name: no cycle statistics: $(cat "$WORK/$name.cli")"
  for passes in 1 2; do
    pass_option=()
    [ "$passes" = 2 ] && pass_option=(-2)
    run_tshark "$WORK/$name.z$passes" "$cap" "${pass_option[@]}" -q -z ncservo,timing
    timing_block "$WORK/$name.z$passes" >"$WORK/$name.plugin$passes"
    diff -u "$WORK/$name.cli" "$WORK/$name.plugin$passes" ||
      fail "$name: tshark ${pass_option[*]} -z ncservo,timing differs from validate"
  done
  run_tshark "$WORK/$name.fields" "$cap" -2 -T fields -E occurrence=f -e ncservo.cycle.interval \
    -e ncservo.latency
  # tshark 4.0's io,stat leaves the first row's floating-point sums unset (register_io_tap sets
  # only the integer counters): glibc's MALLOC_PERTURB_=255 hands it zeroed memory, so the row
  # does not start from whatever the heap held.
  MALLOC_PERTURB_=255 run_tshark "$WORK/$name.iostat" "$cap" -2 -q -z \
    'io,stat,0,AVG(ncservo.cycle.interval)ncservo.cycle.interval,MAX(ncservo.cycle.interval)ncservo.cycle.interval,MAX(ncservo.latency)ncservo.latency'
  python3 - "$WORK/$name" <<'PY' || fail "$name: the per-frame fields disagree with the JSON timing"
import json, math, re, sys
stem = sys.argv[1]
timing = json.load(open(f"{stem}.json"))["captures"][0]["timing"]
columns = {"cycle_us": [], "latency_us": []}
for line in open(f"{stem}.fields"):
    for key, text in zip(columns, line.rstrip("\n").split("\t")):
        if text:
            columns[key].append(float(text))
ok = True
for key, values in columns.items():
    want = timing[key]
    if want is None:
        if values:
            ok = False
            print(f"{key}: {len(values)} per-frame values, none in the JSON timing")
        continue
    values.sort()
    median = values[max(math.ceil(0.5 * len(values)), 1) - 1]  # nearest rank, as docs/timing.md
    got = {"count": len(values), "median": median, "max": values[-1]}
    for stat, value in got.items():
        if abs(value - want[stat]) > 0.0005:
            ok = False
            print(f"{key} {stat}: fields give {value}, JSON {want[stat]}")
# The one interval of `io,stat,0`: AVG and MAX of the intervals, MAX of the latencies.
rows = [line for line in open(f"{stem}.iostat") if re.match(r"\|\s*0(\.0+)? <> ", line)]
if len(rows) != 1:
    sys.exit(f"io,stat: {len(rows)} rows for the whole capture")
numbers = [float(x) for x in re.findall(r"\|\s*(-?\d+(?:\.\d+)?)\s*(?=\|)", rows[0])]
cycle, latency = timing["cycle_us"], timing["latency_us"]
expected = [cycle["mean"], cycle["max"], latency["max"] if latency else 0.0]
if len(numbers) != 3 or any(abs(a - b) > 0.0005 for a, b in zip(numbers, expected)):
    ok = False
    print(f"io,stat gives {numbers}, the JSON timing {expected}")
sys.exit(0 if ok else 1)
PY
  echo "$name: $(head -1 "$WORK/$name.cli" | cut -c1-120)"
done
echo "plugin_timing: tshark -z ncservo,timing prints validate's numbers; the per-frame fields and io,stat agree with the JSON timing"
