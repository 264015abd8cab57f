#!/usr/bin/env bash
# simulate_captures.sh SRC BUILD
# Each simulated capture in captures/ is exactly what its documented command regenerates (and so
# is its layout file); `ncservo validate` on it, with no configuration (the layout learned from
# its start-up), gives its golden report, and the same findings as with its layout file; it
# triggers exactly the rules captures/README.md says, each on the frames the simulator's plan
# gives it (--faults-truth, check_findings.py; the incidents capture: incident_truth); the fault
# table there is `ncservo simulate --list-faults`.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
readme="$SRC/captures/README.md"
for name in sim-commissioning-4axis.pcap sim-faults-4axis.pcap sim-io-interleaved.pcapng \
  sim-incidents-4axis.pcap; do
  stem=${name%.*}
  row=$(grep "^| \`$name\`" "$readme") || fail "no row for $name in captures/README.md"
  cmd=$(grep -o "build/validator/ncservo simulate [^\`]*-o captures/$name[^\`]*" <<<"$row")
  [ -n "$cmd" ] || fail "no regeneration command for $name"
  cmd=${cmd//captures\//$WORK/}
  cmd=${cmd/build\/validator\/ncservo/$NCSERVO}
  # Beside the regeneration, the findings its faults must produce, from the simulator's plan (not
  # for the incidents capture, whose truth is its incidents).
  truth=()
  [ -f "$SRC/captures/$stem.incidents.json" ] || truth=(--faults-truth "$WORK/$stem.faults.json")
  eval "$cmd \"\${truth[@]}\"" 2>"$WORK/sim.err" || fail "$name: simulate exit $?: $(cat "$WORK/sim.err")"
  cmp "$SRC/captures/$name" "$WORK/$name" || fail "$name differs from its regeneration"
  if [ -f "$SRC/captures/$stem.incidents.json" ]; then
    cmp "$SRC/captures/$stem.incidents.json" "$WORK/$stem.incidents.json" ||
      fail "$stem.incidents.json differs from its regeneration"
  fi
  if [ -f "$SRC/captures/$stem.toml" ]; then
    cmp "$SRC/captures/$stem.toml" "$WORK/$stem.toml" || fail "$stem.toml differs from its regeneration"
    # The layout file gives the findings the start-up's learned layout gives: the same rules on
    # the same frames (a finding before the FMMUs are configured names its axis only with the
    # file, which knows the axes from the first frame).
    "$NCSERVO" validate --config "$SRC/captures/$stem.toml" --format jsonl --fail-on never \
      "$SRC/captures/$name" | { grep -o '"rule":"[^"]*"\|"frame":[0-9]*' || true; } | paste -d' ' - - >"$WORK/with-config.txt"
    "$NCSERVO" validate --format jsonl --fail-on never "$SRC/captures/$name" |
      { grep -o '"rule":"[^"]*"\|"frame":[0-9]*' || true; } | paste -d' ' - - >"$WORK/learned.txt"
    [ -s "$WORK/learned.txt" ] || [ ! -s "$WORK/with-config.txt" ] || fail "$name: no findings learned"
    diff -q "$WORK/with-config.txt" "$WORK/learned.txt" >/dev/null ||
      fail "$name: findings with $stem.toml differ from the learned layout's"
  fi
  size=$(stat -c %s "$SRC/captures/$name")
  [ "$size" -lt 2000000 ] || fail "$name is $size bytes; bundled captures stay under 2 MB"

  "$NCSERVO" validate --format json --fail-on never "$SRC/captures/$name" \
    >"$WORK/$stem.json" || fail "$name: validate exit $?"
  python3 "$SRC/tests/tools/golden.py" <"$WORK/$stem.json" >"$WORK/$stem.golden.json"
  diff -u "$SRC/captures/$stem.expected.json" "$WORK/$stem.golden.json" >"$WORK/diff.txt" ||
    fail "$name: report differs from captures/$stem.expected.json: $(head -40 "$WORK/diff.txt")"

  # tshark's stock dissector takes every frame, faults included, without complaint
  "$TSHARK" none -r - -Y "_ws.malformed || _ws.expert" -T fields -e frame.number \
    <"$SRC/captures/$name" >"$WORK/stock.txt" 2>"$WORK/tshark.err" || fail "$name: tshark exit $?"
  [ ! -s "$WORK/stock.txt" ] || fail "$name: the stock dissector flags frames $(head -c 200 "$WORK/stock.txt")"

  # the rules column: "none", "all 29", or a list of rule IDs
  must=$(awk -F'|' '{ print $4 }' <<<"$row" | xargs)
  python3 - "$WORK/$stem.json" "$must" <<'PY' || fail "$name: fired rules differ from captures/README.md"
import json, sys
findings = json.load(open(sys.argv[1]))["captures"][0]["findings"]
fired = sorted({f["rule"] for f in findings})
must = sys.argv[2]
if must == "none":
    want = []
elif must.startswith("all"):
    import subprocess
    want = None  # every rule: compared by count with the catalogue below
else:
    want = sorted(must.replace(",", " ").split())
if want is None:
    count = int(must.split()[1])
    assert len(fired) == count, f"{len(fired)} rules fired, expected all {count}: {fired}"
else:
    assert fired == want, f"fired {fired}, README says {want}"
PY

  # The findings' frames against that plan, with the layout file (which names an axis from the
  # first frame): the golden report is the validator's own, this check is not.
  if [ ${#truth[@]} -gt 0 ]; then
    config=()
    [ ! -f "$SRC/captures/$stem.toml" ] || config=(--config "$SRC/captures/$stem.toml")
    "$NCSERVO" validate "${config[@]}" --format json --fail-on never "$SRC/captures/$name" \
      >"$WORK/$stem.planned.json" || fail "$name: validate exit $?"
    python3 "$SRC/tests/tools/check_findings.py" "$WORK/$stem.planned.json" "$WORK/$stem.faults.json" ||
      fail "$name: findings differ from the simulator's plan (--faults-truth)"
  fi
done
# The fault table of captures/README.md is the simulator's own (no drift).
"$NCSERVO" simulate --list-faults | tail -n +2 |
  awk '{ rule=$1; comp=$2; $1=""; $2=""; sub(/^  */, ""); printf "| %s | %s | %s |\n", rule, comp, $0 }' \
  >"$WORK/faults.md"
grep -E '^\| [A-Z]+-[0-9]{3} \|' "$readme" >"$WORK/readme-faults.md"
diff -u "$WORK/readme-faults.md" "$WORK/faults.md" >"$WORK/diff.txt" ||
  fail "captures/README.md's fault table differs from simulate --list-faults: $(cat "$WORK/diff.txt")"
[ "$(wc -l <"$WORK/faults.md")" = "$("$NCSERVO" rules | wc -l)" ] || fail "not every rule has a fault"
echo "simulate_captures: regenerated byte for byte, golden reports, documented rules and faults"
