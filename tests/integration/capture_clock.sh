#!/usr/bin/env bash
# capture_clock.sh SRC BUILD
# A capture is not the bus (docs/timing.md#the-clock, docs/cli.md): on recordings whose stamps the
# capturing PC bunched into 4 ms bursts, quantised to 1 ms or made late by up to 400 us, and on
# recordings holding every record twice, `ncservo validate` with no configuration finds what it
# finds on the same bus stamped well — the same findings and incidents, on the same frames (the
# first of each pair of copies), none on a healthy bus, exactly the lost cycles on a bus that lost
# some — names the clock that judged it (`bus` for the stamps, `capture` for the copies) and says
# why, keeps the cycle median within 1 % of the bus's, and counts the duplicates. `tshark -2` with
# the plugin shows the same findings on the same frames and ncservo.clock. The simulator writes
# the shapes, and apart from it the independent generator (tests/tools/gen_capture.py) with
# injected violations, checked against its own list of them.
# --quick (the sanitizer build, which looks for memory errors, not at every row): the faults and
# incidents runs, bunched stamps and copies only; the generator's bunched stamps and copies.
SRC=$1 BUILD=$2 QUICK=${3:-}
source "$SRC/tests/integration/lib.sh"

# summary JSON [PAIRED]: one line per finding (rule, axis, frame) and incident (cause, axis,
# frame); PAIRED: the capture holds every record twice, its frame n the plain run's (n + 1) / 2.
summary() {
  python3 - "$1" "${2:-}" <<'PY'
import json, sys
capture = json.load(open(sys.argv[1]))["captures"][0]
paired = sys.argv[2] == "paired"
frame = lambda n: (n + 1) // 2 if paired and n is not None else n
for f in capture["findings"]:
    print("finding", f["rule"], f["axis"], frame(f["frame"]))
for i in capture["incidents"]:
    print("incident", i["cause"]["id"], i.get("axis"), frame(i.get("frame")))
PY
}

# field JSON EXPRESSION: a value of the capture's report, by a Python expression on `c`.
field() {
  python3 -c 'import json, sys; c = json.load(open(sys.argv[1]))["captures"][0]; print(eval(sys.argv[2]))' "$1" "$2"
}

validate() { # CAPTURE OUT.json
  local rc=0
  "$NCSERVO" validate --format json --fail-on never "$1" >"$2" 2>"$WORK/err.txt" || rc=$?
  [ $rc = 0 ] || fail "$(basename "$1"): validate exit $rc: $(head -3 "$WORK/err.txt")"
}

# The plugin's findings on each frame (tshark -2) against validate's on the same capture, and
# the clock it names on the frames with a cycle interval.
plugin_agrees() { # CAPTURE REPORT.json CLOCK
  local capture=$1 report=$2 clock=$3
  chmod a+r "$capture"
  "$TSHARK" "$PLUGIN" -2 -r "$capture" -Y ncservo.finding -T fields -E occurrence=a \
    -E aggregator='|' -e frame.number -e ncservo.finding >"$WORK/plugin.tsv" 2>"$WORK/tshark.err" ||
    fail "$(basename "$capture"): tshark exit $?: $(head -3 "$WORK/tshark.err")"
  python3 - "$report" "$WORK/plugin.tsv" <<'PY' || fail "$(basename "$capture"): tshark -2 differs from validate"
import collections, json, sys
report = json.load(open(sys.argv[1]))["captures"][0]
want = collections.Counter((f["frame"], f["rule"]) for f in report["findings"] if f["frame"])
got = collections.Counter()
for line in open(sys.argv[2]):
    frame, findings = line.rstrip("\n").split("\t")
    for text in findings.split("|"):
        got[(int(frame), text.split(" ")[0])] += 1
if want != got:
    print("validate only:", sorted((want - got).elements())[:5], "tshark only:",
          sorted((got - want).elements())[:5])
    sys.exit(1)
PY
  local clocks
  clocks=$("$TSHARK" "$PLUGIN" -2 -r "$capture" -Y ncservo.cycle.interval -T fields \
    -e ncservo.clock | sort -u | xargs)
  [ "$clocks" = "$clock" ] || fail "$(basename "$capture"): tshark -2 ncservo.clock '$clocks', not $clock"
}

# compare NAME PLAIN SHAPED CLOCK [paired]: the shaped capture judged as the plain one.
compare() {
  local name=$1 plain=$2 shaped=$3 clock=$4 paired=${5:-}
  validate "$plain" "$WORK/plain.json"
  validate "$shaped" "$WORK/shaped.json"
  summary "$WORK/plain.json" >"$WORK/plain.txt"
  summary "$WORK/shaped.json" "$paired" >"$WORK/shaped.txt"
  diff -u "$WORK/plain.txt" "$WORK/shaped.txt" >"$WORK/diff.txt" ||
    fail "$name: findings or incidents differ from the well-stamped capture's: $(head -12 "$WORK/diff.txt")"
  local source why median plain_median
  source=$(field "$WORK/shaped.json" 'c["clock"]["source"]')
  why=$(field "$WORK/shaped.json" 'c["clock"]["why"]')
  [ "$source" = "$clock" ] || fail "$name: clock $source, not $clock ($why)"
  [ -n "$why" ] || fail "$name: the clock says no why"
  median=$(field "$WORK/shaped.json" 'c["timing"]["cycle_us"]["median"]')
  plain_median=$(field "$WORK/plain.json" 'c["timing"]["cycle_us"]["median"]')
  python3 -c "import sys; a, b = float(sys.argv[1]), float(sys.argv[2]); sys.exit(abs(a - b) > b / 100)" \
    "$median" "$plain_median" || fail "$name: cycle median $median us, the bus's $plain_median us"
  plugin_agrees "$shaped" "$WORK/shaped.json" "$clock"
  echo "  $name: $(wc -l <"$WORK/shaped.txt") findings and incidents as on good stamps; clock $source ($why)"
}

sim() { # OUT ARGS...: a simulated capture, 250 us cycle
  local out=$1
  shift
  "$NCSERVO" simulate --cycle-us 250 "$@" -o "$out" 2>"$WORK/sim.err" ||
    fail "simulate $*: $(head -3 "$WORK/sim.err")"
}

declare -A runs=(
  [healthy]="--duration 3 --seed 3"
  [faults]="--scenario faults --seed 5"
  [lost]="--duration 3 --seed 3 --lost-cycles 1.5:3"
  [incidents]="--scenario incidents --seed 2"
)
sim_runs=(healthy faults lost incidents) sim_shapes=(bunched:4ms quantised:1ms late:400us)
gen_shapes=(bunched:4ms quantised:1ms late:400us duplicates)
if [ "$QUICK" = --quick ]; then
  sim_runs=(faults incidents) sim_shapes=(bunched:4ms) gen_shapes=(bunched:4ms duplicates)
fi
for run in "${sim_runs[@]}"; do
  # shellcheck disable=SC2086
  sim "$WORK/$run.pcap" ${runs[$run]}
  for shape in "${sim_shapes[@]}"; do
    # shellcheck disable=SC2086
    sim "$WORK/$run-${shape%%:*}.pcap" ${runs[$run]} --capture-stamps "$shape"
    compare "$run --capture-stamps $shape" "$WORK/$run.pcap" "$WORK/$run-${shape%%:*}.pcap" bus
  done
  # shellcheck disable=SC2086
  sim "$WORK/$run-twice.pcap" ${runs[$run]} --duplicate-records
  compare "$run --duplicate-records" "$WORK/$run.pcap" "$WORK/$run-twice.pcap" capture paired
  records=$(field "$WORK/plain.json" 'c["frames"]')
  duplicates=$(field "$WORK/shaped.json" 'c["duplicates"]')
  [ "$duplicates" = "$records" ] || fail "$run --duplicate-records: $duplicates duplicates, not $records"
done
# A healthy bus: no finding, however it was stamped (the drive fault it carries is an incident).
for spec in bunched:4ms quantised:1ms late:400us; do
  shape=${spec%%:*}
  # shellcheck disable=SC2086
  [ -f "$WORK/healthy-$shape.pcap" ] ||
    sim "$WORK/healthy-$shape.pcap" ${runs[healthy]} --capture-stamps "$spec"
  validate "$WORK/healthy-$shape.pcap" "$WORK/h.json"
  [ "$(field "$WORK/h.json" 'len(c["findings"])')" = 0 ] ||
    fail "healthy --capture-stamps $shape: findings on a healthy bus"
done
"$NCSERVO" validate "$WORK/healthy-bunched.pcap" >"$WORK/h.txt" || fail "healthy bunched: exit $?"
grep -q '^clock: bus (reference clock 0x[0-9a-f]*, FRMW of 0x0910); capture stamps bunched into 4 ms bursts' \
  "$WORK/h.txt" || fail "the text report's clock line: $(grep '^clock' "$WORK/h.txt")"
# The plugin's timing block is validate's, on the bus's clock.
"$TSHARK" "$PLUGIN" -2 -r "$WORK/healthy-bunched.pcap" -q -z ncservo,timing >"$WORK/z.txt" 2>&1 ||
  fail "tshark -z ncservo,timing: exit $?"
grep -E '^timing \(|^  (return|worst)' "$WORK/h.txt" >"$WORK/h.timing"
grep -E '^timing \(|^  (return|worst)' "$WORK/z.txt" >"$WORK/z.timing"
grep -q '^timing (bus timestamps, 1 ns): cycle .* median 250.000 ' "$WORK/h.timing" ||
  fail "healthy bunched: the timing block: $(head -1 "$WORK/h.timing")"
diff -u "$WORK/h.timing" "$WORK/z.timing" >"$WORK/z.diff" ||
  fail "tshark -2 -z ncservo,timing differs from validate: $(head -8 "$WORK/z.diff")"
# shellcheck disable=SC2086
[ -f "$WORK/healthy-twice.pcap" ] || sim "$WORK/healthy-twice.pcap" ${runs[healthy]} --duplicate-records
"$NCSERVO" validate "$WORK/healthy-twice.pcap" >"$WORK/h.txt" || fail "healthy twice: exit $?"
grep -q '^duplicates: [0-9]* records ignored (the first: frame 2)' "$WORK/h.txt" ||
  fail "the text report's duplicates line: $(grep '^dup' "$WORK/h.txt")"
# Wireshark marks each copy, and only the copies: the even frames.
# shellcheck disable=SC2086
[ -f "$WORK/healthy.pcap" ] || sim "$WORK/healthy.pcap" ${runs[healthy]}
validate "$WORK/healthy.pcap" "$WORK/h.json"
records=$(field "$WORK/h.json" 'c["frames"]')
"$TSHARK" "$PLUGIN" -2 -r "$WORK/healthy-twice.pcap" -Y ncservo.duplicate -T fields \
  -e frame.number >"$WORK/copies.txt" 2>&1 || fail "tshark -Y ncservo.duplicate: exit $?"
awk '$1 % 2 == 1 { odd++ } END { exit odd > 0 || NR != '"$records"' }' "$WORK/copies.txt" ||
  fail "tshark -2 marks $(wc -l <"$WORK/copies.txt") records as duplicates, not the $records copies"

# The independent generator, with injected violations, against its own list of them.
for shape in "${gen_shapes[@]}"; do
  args=(--capture-stamps "$shape")
  [ $shape = duplicates ] && args=(--duplicate-records)
  python3 "$GEN" --axes 4 --cycles 12000 --cycle-us 250 --inject SE-001@0.8:1 --inject COM-002@1.6 \
    "${args[@]}" -o "$WORK/gen.pcap" --findings "$WORK/gen.findings.json" ||
    fail "gen_capture.py ${args[*]}"
  validate "$WORK/gen.pcap" "$WORK/gen.json"
  python3 "$SRC/tests/tools/check_findings.py" "$WORK/gen.json" "$WORK/gen.findings.json" \
    >"$WORK/check.txt" 2>&1 || fail "gen_capture.py ${args[*]}: $(head -5 "$WORK/check.txt")"
  clock=bus
  [ $shape = duplicates ] && clock=capture
  [ "$(field "$WORK/gen.json" 'c["clock"]["source"]')" = $clock ] ||
    fail "gen_capture.py ${args[*]}: clock $(field "$WORK/gen.json" 'c["clock"]')"
  plugin_agrees "$WORK/gen.pcap" "$WORK/gen.json" $clock
  echo "  gen_capture.py ${args[*]}: the injected violations found; clock $clock"
done
echo "capture_clock: every shape judged as on good stamps, in validate and tshark -2"
