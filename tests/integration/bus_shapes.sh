#!/usr/bin/env bash
# bus_shapes.sh SRC BUILD [SHAPE...]: the shapes of a machine's real bus (docs/simulate.md#shapes),
# each made by the simulator and, where it can express it, by the independent generator
# (gen_capture.py), with its truth: the exact layout and the injected violations. For each shape,
# with no configuration:
# - `validate` finds every injected violation and reports nothing else, of any severity, but the
#   injections' companions (check_findings.py for the generator's captures);
# - its findings equal those with the exact `--config` (JSON Lines, byte for byte);
# - `tshark -2` with the plugin shows the findings validate reports, on the same frames, and the
#   same as with the exact configuration (ncservo.config);
# - for the starts inside a fault and the second task's cases, validate and tshark -2 decode as many
#   axes as the exact layout holds.
# And an idle 4-axis capture (nothing enabled anywhere) decodes all 4 axes (validate, decode and
# tshark -2), says they were found from the structure only (text and JSON report, an expert note
# in tshark -2), and yields no finding.
# SHAPE... (optional): run only the cases whose names are given.
SRC=$1 BUILD=$2
shift 2
source "$SRC/tests/integration/lib.sh"
ONLY=("$@")

failures=()
passes=()
# case_failed NAME WHY: note a failing case and go on with the others.
case_failed() {
  echo "FAIL: $1: $2" >&2
  local f
  for f in "${failures[@]}"; do [ "$f" = "$1" ] && return 0; done
  failures+=("$1")
}

# The companions each simulated fault brings (simulate --list-faults), as JSON.
"$NCSERVO" simulate --list-faults | python3 -c '
import json, sys
rows = [line.split(None, 2) for line in sys.stdin][1:]
print(json.dumps({r[0]: [] if r[1] == "-" else r[1].split(",") for r in rows}))
' >"$WORK/companions.json"

# sim_truth NAME CAPTURE.expected.json [RULE:AXIS...]: the expectation of a simulated capture in
# check_findings.py's form (each injected rule on its axis, anywhere in the capture).
sim_truth() {
  local out=$1
  shift
  python3 - "$out" "$WORK/companions.json" "$@" <<'PY'
import json, sys
out, companions = sys.argv[1], json.load(open(sys.argv[2]))
expected, rules = [], set()
for item in sys.argv[3:]:
    rule, _, axis = item.partition(":")
    rules.add(rule)
    expected.append({"rule": rule, "axis": int(axis) if axis else None,
                     "first_frame": 1, "last_frame": 10**9, "due_frame": 1})
json.dump({"expected": expected,
           "companions": {r: companions.get(r, []) for r in sorted(rules) if companions.get(r)}},
          open(out, "w"))
PY
}

# judge NAME CAPTURE LAYOUT EXPECTED: the checks of the header on one capture; 0 when all hold.
judge() {
  local name=$1 cap=$2 layout=$3 expected=$4 dir="$WORK/$1"
  mkdir -p "$dir"
  chmod a+r "$cap" "$layout"
  local rc=0
  "$NCSERVO" validate --format json --fail-on never "$cap" >"$dir/free.json" 2>"$dir/err.txt" ||
    rc=$?
  # 4: NO SERVO, a finding of its own (the checks below say what it misses)
  [ $rc = 0 ] || [ $rc = 4 ] ||
    { case_failed "$name" "validate exit $rc: $(head -3 "$dir/err.txt")"; return 1; }
  "$NCSERVO" validate --format jsonl --fail-on never "$cap" >"$dir/free.jsonl" 2>/dev/null
  "$NCSERVO" validate --format jsonl --fail-on never --config "$layout" "$cap" \
    >"$dir/configured.jsonl" 2>"$dir/err.txt" ||
    { case_failed "$name" "validate --config exit $?: $(head -3 "$dir/err.txt")"; return 1; }
  "$NCSERVO" validate --fail-on never "$cap" >"$dir/free.txt" 2>&1 || true
  if [ $rc = 4 ]; then
    case_failed "$name" "NO SERVO with no configuration: $(grep -m1 '^NO SERVO' "$dir/free.txt" |
      cut -c1-220)"
  fi
  local ok=0
  if ! python3 "$SRC/tests/tools/check_findings.py" "$dir/free.json" "$expected" \
    >"$dir/check.txt" 2>&1; then
    case_failed "$name" "validate with no configuration: $(grep -m1 -E '^(check_findings|NO SERVO)' \
      "$dir/check.txt") [$(grep -m1 '^layout' "$dir/free.txt"); $(grep -m1 'NO SERVO' \
      "$dir/free.txt" | cut -c1-160)] $(grep -m3 '^[-+] ' "$dir/check.txt" | cut -c1-140 |
      tr '\n' ';')"
    ok=1
  fi
  if ! cmp -s <(grep '"rule"' "$dir/free.jsonl") <(grep '"rule"' "$dir/configured.jsonl"); then
    case_failed "$name" "findings differ from those with the exact --config: $(diff \
      <(grep '"rule"' "$dir/free.jsonl" | cut -c1-160) \
      <(grep '"rule"' "$dir/configured.jsonl" | cut -c1-160) | grep -c '^[<>]') lines"
    ok=1
  fi
  # The plugin in two passes, without and with the exact layout.
  local pass
  for pass in free configured; do
    local prefs=()
    [ $pass = configured ] && prefs=(-o "ncservo.config:$layout")
    "$TSHARK" "$PLUGIN" -2 -r "$cap" "${prefs[@]}" -Y ncservo.finding -T fields -E occurrence=a \
      -E aggregator='|' -e frame.number -e ncservo.finding >"$dir/plugin-$pass.tsv" \
      2>"$dir/tshark.err" ||
      { case_failed "$name" "tshark exit $?: $(head -3 "$dir/tshark.err")"; return 1; }
    [ ! -s "$dir/tshark.err" ] ||
      { case_failed "$name" "tshark stderr: $(head -3 "$dir/tshark.err")"; return 1; }
  done
  if ! cmp -s "$dir/plugin-free.tsv" "$dir/plugin-configured.tsv"; then
    case_failed "$name" "tshark -2: findings with no configuration differ from those with \
ncservo.config ($(diff "$dir/plugin-free.tsv" "$dir/plugin-configured.tsv" | grep -c '^[<>]') lines)"
    ok=1
  fi
  if ! python3 - "$dir/free.json" "$dir/plugin-free.tsv" >"$dir/plugin-check.txt" <<'PY'; then
import collections, json, sys
findings = json.load(open(sys.argv[1]))["captures"][0]["findings"]
want = collections.Counter((f["frame"], f["rule"]) for f in findings)
shown = collections.Counter()
for line in open(sys.argv[2]):
    if not line.strip():
        continue
    frame, texts = line.rstrip("\n").split("\t")
    for text in texts.split("|"):
        shown[(int(frame), text.split(" ")[0])] += 1
if set(want) != set(shown):
    print(f"validate only: {sorted(set(want) - set(shown))[:4]}; "
          f"plugin only: {sorted(set(shown) - set(want))[:4]}")
    sys.exit(1)
PY
    case_failed "$name" "tshark -2 with no configuration and validate disagree: $(cat "$dir/plugin-check.txt")"
    ok=1
  fi
  [ $ok = 0 ] && [ $rc = 0 ] && passes+=("$name")
  return $ok
}

wanted() {
  [ ${#ONLY[@]} = 0 ] && return 0
  local n
  for n in "${ONLY[@]}"; do [ "$n" = "$1" ] && return 0; done
  return 1
}

# sim_case NAME "SIMULATE OPTIONS" RULE:AXIS...: a simulated shape and its injected faults.
sim_case() {
  local name=$1 options=$2
  shift 2
  wanted "$name" || return 0
  local cap="$WORK/$name.pcap"
  # shellcheck disable=SC2086  # the options are words
  if ! "$NCSERVO" simulate $options -o "$cap" --layout-config "$WORK/$name.toml" \
    >/dev/null 2>"$WORK/$name.err"; then
    case_failed "$name" "simulate exit: $(cat "$WORK/$name.err")"
    return
  fi
  local faults=()
  for item in "$@"; do faults+=("$item"); done
  sim_truth "$WORK/$name.expected.json" "${faults[@]}"
  judge "$name" "$cap" "$WORK/$name.toml" "$WORK/$name.expected.json" || true
}

# gen_case NAME "GENERATOR OPTIONS": a shape of the independent generator, with its findings.
gen_case() {
  local name=$1 options=$2
  wanted "$name" || return 0
  local cap="$WORK/$name.pcap"
  # shellcheck disable=SC2086
  if ! python3 "$GEN" $options -o "$cap" --layout-config "$WORK/$name.toml" \
    --findings "$WORK/$name.expected.json" 2>"$WORK/$name.err"; then
    case_failed "$name" "gen_capture.py: $(cat "$WORK/$name.err")"
    return
  fi
  judge "$name" "$cap" "$WORK/$name.toml" "$WORK/$name.expected.json" || true
}

faults="--fault SE-001@1.0:0 --fault MSG-001@1.2:1"
# I/O neighbours whose inputs change every cycle, the servos at odd offsets of the same LRW.
sim_case sim-io-busy-soem "--no-startup --image soem --io-slaves 5 --io-inputs cycle $faults" \
  SE-001:0 MSG-001:1
for seed in 1 2 3; do
  sim_case "sim-io-busy-mixed-$seed" "--no-startup --image mixed --io-inputs cycle --seed $seed \
$faults" SE-001:0 MSG-001:1
done
sim_case sim-io-busy-etherlab "--no-startup --image etherlab --io-slaves 3 --io-inputs cycle \
$faults" SE-001:0 MSG-001:1
gen_case gen-io-busy "--cycles 3000 --io-terminals 3 --inject SE-001 --inject MSG-001"
# CiA 402 neighbours with 10/40-byte PDOs.
sim_case sim-cia402 "--no-startup --cia402 2 $faults" SE-001:0 MSG-001:1
sim_case sim-cia402-mixed "--no-startup --image mixed --cia402 3 --seed 4 $faults" SE-001:0 MSG-001:1
gen_case gen-cia402 "--cycles 3000 --cia402 1 --inject SE-001 --inject MSG-001"
# Idle for seconds after the start, or for the whole capture.
sim_case sim-idle-start "--no-startup --idle 1.5 --duration 4 --fault SE-001@2.2:0 \
--fault MSG-001@2.3:1" SE-001:0 MSG-001:1
sim_case sim-idle-start-long "--no-startup --idle 6 --duration 8 --fault SE-003@6.7:2" SE-003:2
gen_case gen-idle-start "--cycles 6000 --idle-cycles 4500 --inject SE-001@5.0:0 --inject MSG-001@5.2:1"
sim_case sim-idle-all "--no-startup --idle all" # no finding
gen_case gen-idle-all "--idle-all"
# A start in the middle of a fault, an error clear or a homing, the first enables faulty.
for moment in fault error-clear homing; do
  sim_case "sim-start-in-$moment" "--start-in $moment --duration 5 --fault SE-001@1.6:0 \
--fault SE-004@1.7:2 --fault MSG-001@1.8:3" SE-001:0 SE-004:2 MSG-001:3
done
# Already enabled when the capture starts: the first enable edges it shows are the faulty ones.
sim_case sim-start-in-homing-faulty-enables "--start-in homing --duration 5 --fault SE-001@1.2:0 \
--fault SE-001@1.3:2 --fault SE-004@1.4:3 --fault SE-002@1.5:1" SE-001:0 SE-001:2 SE-004:3 SE-002:1
# A start inside a drive fault whose NC has already dropped SE to 0x1 while the drive holds
# ServoEn beside its error for 200 ms (SE-001's disable at FLT-001's moment, docs/layout.md): the
# structure decides, and the broken handshake is SE-003's and FLT-001's, on the frames the exact
# layout gives. The simulator drops SE-001's own illegal enable here (the NC is handling the
# fault at its moment), so SE-001 is not expected.
sim_case sim-start-in-flt001-se-dropped "--start-in fault:FLT-001 --fault FLT-001@0.8:2 \
--fault SE-001@0.95:2" SE-003:2 FLT-001:2
sim_case sim-start-in-flt001-se-dropped-1ax "--axes 1 --start-in fault:FLT-001 \
--fault FLT-001@0.8:0 --fault SE-001@0.95:0" SE-003:0 FLT-001:0
sim_case sim-start-in-flt001-se-dropped-twincat "--image twincat --axes 3 --cycle-us 2000 \
--start-in fault:FLT-001 --fault FLT-001@0.8:1 --fault SE-001@0.95:1" SE-003:1 FLT-001:1
sim_case sim-start-in-se003-250us "--image etherlab --cycle-us 250 --start-in fault:SE-003 \
--fault SE-003@1.0:2" SE-003:2
# ... and among the mixed image's CiA 402 drive, whose torque reads SE 0x2 beside the ServoEn the
# capture begins with until it steps: the window waits for a handshake it sees happen.
sim_case sim-start-in-se003-mixed-250us "--image mixed --cycle-us 250 --axes 2 --seed 43 \
--start-in fault:SE-003 --fault SE-003@0.9:1" SE-003:1
# A second task: a 10 ms I/O frame with its own datagram list beside the 1 ms servo frames.
sim_case sim-second-task "--no-startup --io-slaves 4 --io-task-us 10000 $faults" SE-001:0 MSG-001:1
# Healthy, beside 8 terminals of a 10 ms task, at 1 ms and 250 us: no finding. At 250 us a CiA 402
# drive's torque (the mixed image) reads as a control word agreeing with every ServoEn for its
# first 50 ms; the early decision waits until it steps (docs/layout.md).
sim_case sim-second-task-8 "--no-startup --io-slaves 8 --io-task-us 10000"
sim_case sim-second-task-8-mixed-homing "--io-slaves 8 --io-task-us 10000 --image mixed \
--cycle-us 250 --start-in homing"
sim_case sim-second-task-16-mixed-homing "--io-slaves 16 --io-task-us 10000 --image mixed \
--cycle-us 250 --axes 6 --seed 4 --start-in homing"
sim_case sim-second-task-mixed "--no-startup --image mixed --io-task-us 4000 --cycle-us 500 --seed 2 \
--fault SE-001@1.0:0" SE-001:0
gen_case gen-second-task "--cycles 3000 --io-task-cycles 10 --inject SE-001 --inject SE-003"
# SOEM's echoed inputs in the master copies (the simulator's master always echoes).
sim_case sim-soem-echo "--no-startup --image soem $faults" SE-001:0 MSG-001:1
gen_case gen-soem-echo "--cycles 3000 --echo-inputs --inject SE-001 --inject MSG-001"
# Master copies the capture missed (capture loss, docs/timing.md "Capture loss"): no COM-002,
# COM-003 or COM-005 for them.
sim_case sim-capture-loss "--no-startup --capture-loss 0.03 --seed 5 $faults" SE-001:0 MSG-001:1
# All of it at once.
gen_case gen-machine "--cycles 6000 --io-terminals 5 --cia402 1 --echo-inputs --io-task-cycles 10 \
--idle-cycles 2500 --inject SE-001@4.0 --inject EC-004@4.5"

# axes_check NAME: validate (JSON report) and tshark -2 decode as many axes as the simulator's
# exact layout holds.
axes_check() {
  local name=$1 dir="$WORK/$1"
  wanted "$name" || return 0
  [ -s "$dir/free.json" ] || return 0  # judge said why
  local want got
  want=$(grep -c '^\[\[axis\]\]' "$WORK/$name.toml")
  got=$(python3 -c '
import json, sys
print(len(json.load(open(sys.argv[1]))["captures"][0]["layout"]["axes"]))' "$dir/free.json")
  [ "$got" = "$want" ] || case_failed "$name" "validate decodes $got axes, the layout holds $want"
  "$TSHARK" "$PLUGIN" -2 -r "$WORK/$name.pcap" -Y ncservo -T fields -E occurrence=a \
    -E aggregator=, -e ncservo.axis >"$dir/plugin-axes.txt" 2>/dev/null || true
  got=$(tr ',' '\n' <"$dir/plugin-axes.txt" | awk 'NF' | sort -u | wc -l)
  [ "$got" = "$want" ] || case_failed "$name" "tshark -2 decodes $got axes, the layout holds $want"
}
for name in sim-start-in-flt001-se-dropped sim-start-in-flt001-se-dropped-1ax \
  sim-start-in-flt001-se-dropped-twincat sim-start-in-se003-250us sim-start-in-se003-mixed-250us \
  sim-second-task-8 sim-second-task-8-mixed-homing sim-second-task-16-mixed-homing; do
  axes_check "$name"
done

# An idle 4-axis capture: all 4 axes decoded, found from the structure only, no finding.
idle_check() {
  local name=$1 cap=$2 dir="$WORK/$1-idle"
  wanted "$name" || return 0
  [ -e "$cap" ] || { case_failed "$name" "no capture"; return; }
  mkdir -p "$dir"
  "$NCSERVO" validate --fail-on never "$cap" >"$dir/free.txt" 2>&1 || true
  "$NCSERVO" validate --format json --fail-on never "$cap" >"$dir/free.json" 2>/dev/null || true
  "$NCSERVO" decode --format jsonl "$cap" >"$dir/decode.jsonl" 2>/dev/null || true
  local ok=0 axes
  grep -q '^layout: inferred, 4 axes' "$dir/free.txt" ||
    { case_failed "$name" "idle: $(grep -m1 '^layout' "$dir/free.txt"), expected inferred, 4 axes; \
$(grep -m1 'NO SERVO' "$dir/free.txt" | cut -c1-200)"; ok=1; }
  axes=$(python3 -c '
import json, sys
print(len({json.loads(l).get("axis") for l in open(sys.argv[1]) if l.strip()} - {None}))' \
    "$dir/decode.jsonl")
  [ "$axes" = 4 ] || { case_failed "$name" "idle: decode gives $axes axes, expected 4"; ok=1; }
  grep -qi 'structure' "$dir/free.txt" ||
    { case_failed "$name" "idle: the text report does not say the layout came from the structure only"; ok=1; }
  grep -qi 'structure' "$dir/free.json" ||
    { case_failed "$name" "idle: the JSON report does not say the layout came from the structure only"; ok=1; }
  "$TSHARK" "$PLUGIN" -2 -r "$cap" -Y ncservo -T fields -E occurrence=a -E aggregator=, \
    -e ncservo.axis >"$dir/plugin-axes.txt" 2>/dev/null || true
  axes=$(tr ',' '\n' <"$dir/plugin-axes.txt" | awk 'NF' | sort -u | wc -l)
  [ "$axes" = 4 ] || { case_failed "$name" "idle: tshark -2 decodes $axes axes, expected 4"; ok=1; }
  # Wireshark says it too: an expert note on each axis's layer (docs/plugin.md).
  "$TSHARK" "$PLUGIN" -2 -r "$cap" -Y ncservo.structure_only -T fields -E occurrence=a \
    -E aggregator=, -e ncservo.axis -e _ws.expert.message >"$dir/plugin-notes.txt" 2>&1 || true
  axes=$(cut -f1 "$dir/plugin-notes.txt" | tr ',' '\n' | awk 'NF' | sort -u | wc -l)
  [ "$axes" = 4 ] && grep -q 'layout inferred from the PDO structure alone' "$dir/plugin-notes.txt" ||
    { case_failed "$name" "idle: tshark -2 notes the structure-only layout on $axes axes, expected 4: \
$(head -c 200 "$dir/plugin-notes.txt")"; ok=1; }
  # Once per axis, on its first frame: with no finding, no other frame carries it.
  local notes
  notes=$(grep -o 'layout inferred from the PDO structure alone' "$dir/plugin-notes.txt" | wc -l)
  [ "$notes" = 4 ] || { case_failed "$name" "idle: $notes structure-only notes, expected 4 (one per axis)"; ok=1; }
  grep -q '"rule"' "$dir/free.json" &&
    { case_failed "$name" "idle: findings: $(grep -o '"rule":"[^"]*"' "$dir/free.json" | sort | uniq -c | head -3 | tr '\n' ' ')"; ok=1; }
  [ $ok = 0 ] && passes+=("$name (idle: 4 axes, structure only)")
  return 0
}
idle_check sim-idle-all "$WORK/sim-idle-all.pcap"
idle_check gen-idle-all "$WORK/gen-idle-all.pcap"

echo "bus_shapes: passed: ${passes[*]:-none}"
if [ ${#failures[@]} -gt 0 ]; then
  fail "bus_shapes: ${#failures[@]} failed: ${failures[*]}"
fi
echo "bus_shapes: every shape, with no configuration, reports what the exact configuration reports"
