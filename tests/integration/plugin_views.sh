#!/usr/bin/env bash
# plugin_views.sh SRC BUILD
# The plugin's views against the CLI on the bundled faults capture:
# - each axis is its own ncservo layer: `ncservo.state#N == "S"` selects exactly the frames whose
#   N-th `ncservo decode` row has state S (of those where decode gives one);
# - ncservo.transition appears on exactly the (frame, axis) of the CLI's state timeline, named as
#   there; ncservo.edge on every such change after the first, and SE / ServoEn edges exactly where
#   the decode rows change;
# - the README's FAULT example prints one axis per FAULT transition: the (frame, axis name) pairs
#   of the CLI's state timeline (ncservo.transition.axis_name, where ncservo.axis names them all);
# - ncservo.since_frame equals the CLI's since_frame on every finding;
# - `tshark -z expert` shows one line per rule, counting its findings;
# - readable at many axes: on a simulated 32-axis capture every Info column stays short and names
#   each rule once; -V hides SCW/SSW bits at rest behind one line per word, and filters and
#   -T fields still find them; the status bits whose clear value is the drive's state stay on
#   their own lines (an axis in error shows ServoEn: no).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
cap="$SRC/captures/faults-4axis.pcap"
"$NCSERVO" decode "$cap" >"$WORK/decode.csv" || fail "ncservo decode exited $?"
"$NCSERVO" validate --format json --fail-on never "$cap" >"$WORK/validate.json" ||
  fail "ncservo validate exited $?"

run_tshark() { # OUT tshark-args...
  local out=$1
  shift
  "$TSHARK" "$PLUGIN" -2 -r "$cap" "$@" >"$out" 2>"$WORK/tshark.err" ||
    fail "tshark $* exited $?: $(cat "$WORK/tshark.err")"
  [ ! -s "$WORK/tshark.err" ] || fail "tshark $* printed on stderr: $(head -3 "$WORK/tshark.err")"
}

for layer in 1 2 3 4; do
  for state in "error" "control active" "ready to switch on"; do
    run_tshark "$WORK/layer-$layer-${state// /_}.txt" -Y "ncservo.state#$layer == \"$state\"" \
      -T fields -e frame.number
  done
done
run_tshark "$WORK/views.json" -Y "ncservo.edge || ncservo.transition" -T json --no-duplicate-keys \
  -j "frame ncservo"
run_tshark "$WORK/findings.tsv" -Y ncservo.finding -T fields -E occurrence=a -E aggregator='|' \
  -e frame.number -e ncservo.finding -e ncservo.since_frame
run_tshark "$WORK/expert.txt" -q -z expert
# The README's example as it stands there (its capture path is the repository's).
example=$(grep -o "^tshark -r captures/faults-4axis.pcap -Y 'ncservo.transition == \"FAULT\"' .*" "$SRC/README.md")
[ -n "$example" ] || fail "README.md has no FAULT example"
eval "set -- ${example#tshark }"
(cd "$SRC" && "$TSHARK" "$PLUGIN" "$@") >"$WORK/fault_example.tsv" 2>"$WORK/tshark.err" ||
  fail "the README's FAULT example exited $?: $(cat "$WORK/tshark.err")"

many="$WORK/axes32.pcap"
"$NCSERVO" simulate --scenario faults --axes 32 --seed 5 -o "$many" >/dev/null ||
  fail "ncservo simulate --axes 32 exited $?"
cap=$many run_tshark "$WORK/info32.txt"
# frame 400: a returned copy of the frame with 29 of the axes
rest_filter='frame.number == 400 && ncservo.scw.poslock == 0 && ncservo.ssw.zpulse_ack == 0'
cap=$many run_tshark "$WORK/tree32.txt" -V -O ncservo -c 400 -Y 'frame.number == 400'
cap=$many run_tshark "$WORK/rest32.txt" -c 400 -Y "$rest_filter" -T fields -E occurrence=a \
  -e ncservo.scw.poslock -e ncservo.ssw.zpulse_ack
python3 - "$WORK" <<'PY' || fail "the plugin's views are not readable at 32 axes"
import re, sys
work = sys.argv[1]
ok = True
infos = [m.group(0) for line in open(f"{work}/info32.txt") for m in [re.search(r"\[NCSERVO.*", line)] if m]
if not infos:
    sys.exit("no Info column with [NCSERVO")
longest = max(infos, key=len)
if len(longest) > 140:
    ok = False
    print(f"Info column of {len(longest)} characters at 32 axes: {longest}")
for info in infos:
    rules = re.findall(r"[A-Z]+-\d{3}", info)
    if len(rules) != len(set(rules)):
        ok = False
        print(f"a rule named twice in the Info column: {info}")
        break
tree = open(f"{work}/tree32.txt").read()
axes = tree.count("NC-Servo axis ")
if axes != 29:
    ok = False
    print(f"-V on frame 400 shows {axes} axes, expected 29")
if "= POSLOCK: normal" in tree or "= ZPulseAck: no" in tree:
    ok = False
    print("-V shows SCW/SSW bits at rest one by one")
if tree.count("At rest: ") < axes:
    ok = False
    print(f"-V: {tree.count('At rest: ')} 'At rest' lines for {axes} axes")
lines_per_axis = (len(tree.splitlines()) - 4) / max(axes, 1)
if lines_per_axis > 40:
    ok = False
    print(f"-V: {lines_per_axis:.0f} lines per axis")
# -T fields prints a boolean as 0/1 in tshark 4.0, as False/True from 4.4.
rest = open(f"{work}/rest32.txt").read().replace("False", "0").replace("True", "1").split()
if len(rest) != 2 or any(v != ",".join(["0"] * 29) for v in rest):
    ok = False
    print(f"the hidden bits at rest are not found by a filter and -T fields: {rest[:4]}")
sys.exit(0 if ok else 1)
PY

# An axis in error shows the status bits whose clear value is its state, each on its own line
# (docs/plugin.md): sim-incidents-4axis.pcap frame 3264, the fourth axis (E19).
cap="$SRC/captures/sim-incidents-4axis.pcap" run_tshark "$WORK/tree3264.txt" -V -O ncservo \
  -Y 'frame.number == 3264'
python3 - "$WORK/tree3264.txt" <<'PY' || fail "an axis in error folds its state bits into 'At rest'"
import re, sys
tree = open(sys.argv[1]).read()
axis = tree[tree.index("NC-Servo axis 3 "):]
assert "error" in axis.splitlines()[0], axis.splitlines()[0]
for bit in ("ServoEn: no", "ServoRDY: no", "N=0: no", "N=Ns: no", "PulseEnabled: no"):
    assert re.search(rf"= {re.escape(bit)}$", axis, re.M), f"no line '= {bit}'"
rest = [line for line in axis.splitlines() if "At rest:" in line]
assert not any(re.search(r"ServoEn|ServoRDY|PulseEnabled|N=0|N=Ns", line) for line in rest), rest
PY

python3 - "$WORK" <<'PY' || fail "the plugin's views differ from the CLI's"
import bisect, collections, csv, json, re, sys
work = sys.argv[1]
ok = True
def check(what, expected, actual):
    global ok
    if expected != actual:
        ok = False
        print(f"{what}: expected {sorted(expected)[:10]} got {sorted(actual)[:10]}"
              f" (missing {sorted(expected - actual)[:5]}, extra {sorted(actual - expected)[:5]})")

rows = collections.defaultdict(list)  # frame -> decode rows in axis order
with open(f"{work}/decode.csv") as f:
    for row in csv.DictReader(f):
        rows[int(row["frame"])].append(row)
for layer in range(1, 5):
    for state in ("error", "control active", "ready to switch on"):
        # decode gives a state only with inputs; the plugin also shows it in master copies
        judged = {fr for fr, rs in rows.items() if len(rs) >= layer and rs[layer - 1]["state"]}
        expected = {fr for fr in judged if rows[fr][layer - 1]["state"] == state}
        with open(f"{work}/layer-{layer}-{state.replace(' ', '_')}.txt") as f:
            actual = {int(line) for line in f if line.strip()} & judged
        check(f"ncservo.state#{layer} == {state!r}", expected, actual)

report = json.load(open(f"{work}/validate.json"))["captures"][0]
timeline = {}
first_changes = set()
for axis in report["axes"]:
    for i, change in enumerate(axis["state_timeline"]):
        timeline[(change["frame"], axis["index"])] = change["transition"]
        if i == 0:
            first_changes.add((change["frame"], axis["index"]))
transitions, edges = {}, collections.defaultdict(set)
def layers(value):
    return value if isinstance(value, list) else [value]
for packet in json.load(open(f"{work}/views.json")):
    source = packet["_source"]["layers"]
    frame = int(source["frame"]["frame.number"])
    for layer in layers(source.get("ncservo", [])):
        axis = int(layer["ncservo.axis"])
        if "ncservo.transition" in layer:
            transitions[(frame, axis)] = layer["ncservo.transition"]
        for edge in layers(layer.get("ncservo.edge", [])):
            edges[(frame, axis)].add(edge)
check("ncservo.transition frames", set(timeline), set(transitions))
names = {axis["index"]: axis["name"] for axis in report["axes"]}
faults = {(frame, names[axis]) for (frame, axis), name in timeline.items() if name == "FAULT"}
printed = set()
for line in open(f"{work}/fault_example.tsv"):
    frame, axis = line.rstrip("\n").split("\t")
    if "," in axis:
        ok = False
        print(f"README's FAULT example: frame {frame} prints the axes {axis}")
    printed |= {(int(frame), a) for a in axis.split(",")}
if not faults:
    ok = False
    print("no FAULT transition in the CLI's state timeline")
check("README's FAULT example (frame, axis)", faults, printed)
for key, name in timeline.items():
    if name is not None and transitions.get(key) != name:
        ok = False
        print(f"transition at {key}: expected {name!r}, got {transitions.get(key)!r}")
check("state changes without an edge", set(), set(timeline) - first_changes - set(edges))
# SE and ServoEn edges exactly where the decode rows of the axis change. decode writes a row per
# cycle (at its returned copy); an output's edge is seen first in the master copy before it.
for column, label in (("scw.se", "SE"), ("ssw.servo_en", "ServoEn")):
    expected, last, row_frames = set(), {}, collections.defaultdict(list)
    for frame in sorted(rows):
        for row in rows[frame]:
            if row[column] == "":
                continue
            axis = int(row["axis"])
            row_frames[axis].append(frame)
            if axis in last and last[axis] != row[column]:
                expected.add((frame, axis))
            last[axis] = row[column]
    def cycle_row(frame, axis):
        frames = row_frames[axis]
        i = bisect.bisect_left(frames, frame)
        return (frames[i] if i < len(frames) else frame, axis)
    actual = {cycle_row(*key) for key, texts in edges.items()
              if any(t.split(" ")[0] == label for t in texts)}
    check(f"{label} edges", expected, actual)

expected = collections.Counter()
for finding in report["findings"]:
    expected[(finding["frame"], finding["rule"], finding["since_frame"])] += 1
actual = collections.Counter()
with open(f"{work}/findings.tsv") as f:
    for line in f:
        frame, texts, sinces = line.rstrip("\n").split("\t")
        for text, since in zip(texts.split("|"), sinces.split("|")):
            actual[(int(frame), text.split(" ")[0], int(since))] += 1
check("findings (frame, rule, since_frame)", set(expected), set(actual))

per_rule = collections.Counter(f["rule"] for f in report["findings"])
lines = collections.Counter()
counts = {}
for line in open(f"{work}/expert.txt"):
    m = re.match(r"\s*(\d+)\s+\S+\s+NCSERVO\s+([A-Z]+-\d{3}) \S+$", line)
    if m:
        lines[m.group(2)] += 1
        counts[m.group(2)] = int(m.group(1))
check("-z expert rules", set(per_rule), set(lines))
for rule, n in lines.items():
    if n != 1 or counts[rule] != per_rule[rule]:
        ok = False
        print(f"-z expert: {rule} on {n} lines counting {counts[rule]}, expected 1 line counting {per_rule[rule]}")
sys.exit(0 if ok else 1)
PY
echo "plugin_views: layers, edges, transitions, since_frame and expert groups match the CLI"
