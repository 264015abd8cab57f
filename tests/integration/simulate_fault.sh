#!/usr/bin/env bash
# simulate_fault.sh SRC BUILD RULE [simulate options...]
# `ncservo simulate --fault RULE` followed by `ncservo validate`, with no configuration (the
# layout learned from the start-up), reports RULE plus only the companions captures/README.md
# documents for it (nothing else at all), and the same with the layout file the simulator wrote;
# tshark with the plugin, with no preference set, shows the finding on exactly the frames the
# validator reports, at the rule's severity and group (lib.sh rule_frames). A rule off by default
# (COM-006, COM-007) is enabled for all of them.
SRC=$1 BUILD=$2 RULE=$3
shift 3
source "$SRC/tests/integration/lib.sh"
"$NCSERVO" simulate --fault "$RULE" "$@" -o "$WORK/capture.pcap" --layout-config "$WORK/layout.toml" \
  2>"$WORK/sim.err" || fail "simulate exit $?: $(cat "$WORK/sim.err")"
chmod a+r "$WORK/capture.pcap" "$WORK/layout.toml"
# A rule off by default is enabled: on the command line, and for the plugin in a configuration.
enable=() plugin_prefs=()
if "$NCSERVO" rules --explain "$RULE" | grep -q '^  by default:  off'; then
  enable=(--enable "$RULE")
  printf '[rules]\nenable = ["%s"]\n' "$RULE" >"$WORK/enable.toml"
  plugin_prefs=(-o "ncservo.config:$WORK/enable.toml")
  printf '[rules]\nenable = ["%s"]\n' "$RULE" >>"$WORK/layout.toml"
fi
set +e
"$NCSERVO" validate "${enable[@]}" --format json "$WORK/capture.pcap" >"$WORK/report.json" \
  2>"$WORK/err.txt"
rc=$?
"$NCSERVO" validate --config "$WORK/layout.toml" --format json "$WORK/capture.pcap" \
  >"$WORK/configured.json" 2>>"$WORK/err.txt"
rc2=$?
set -e
[ $rc = 0 ] || [ $rc = 1 ] || fail "validate exit $rc: $(cat "$WORK/err.txt")"
[ $rc2 = $rc ] || fail "validate --config exit $rc2, without $rc: $(cat "$WORK/err.txt")"
python3 - "$WORK/report.json" "$WORK/configured.json" <<'PY' || fail "$RULE: learned and configured layouts disagree"
import json, sys
# The same rules on the same frames; a finding before the FMMUs are configured names its axis
# only with the layout file (learning knows the axes once the start-up has mapped them).
load = lambda p: sorted((f["rule"], f["frame"], f["axis"]) for f in json.load(open(p))["captures"][0]["findings"])
learned, configured = load(sys.argv[1]), load(sys.argv[2])
assert [f[:2] for f in learned] == [f[:2] for f in configured], f"learned {learned}, configured {configured}"
for l, c in zip(learned, configured):
    assert l[2] is None or l[2] == c[2], f"axis {l} vs {c}"
PY
companions=$(grep "^| $RULE |" "$SRC/captures/README.md" | awk -F'|' '{ print $3 }' | xargs)
[ -n "$companions" ] || fail "captures/README.md documents no row for $RULE"
python3 - "$WORK/report.json" "$RULE" "$companions" <<'PY' || fail "$RULE: findings differ"
import json, sys
findings = json.load(open(sys.argv[1]))["captures"][0]["findings"]
rule, companions = sys.argv[2], sys.argv[3]
allowed = {rule} | (set() if companions == "-" else set(companions.split(",")))
fired = {f["rule"] for f in findings}
assert rule in fired, f"{rule} did not fire; fired {sorted(fired)}"
assert fired <= allowed, f"also fired {sorted(fired - allowed)} (allowed {sorted(allowed)})"
PY

rule_frames "$RULE" "$WORK/capture.pcap" "$WORK/plugin.txt" "${plugin_prefs[@]}"
python3 - "$WORK/report.json" "$WORK/plugin.txt" "$RULE" <<'PY' || fail "$RULE: plugin and validator disagree"
import json, sys
findings = json.load(open(sys.argv[1]))["captures"][0]["findings"]
want = sorted({f["frame"] for f in findings if f["rule"] == sys.argv[3]})
shown = sorted({int(l) for l in open(sys.argv[2]) if l.strip()})
assert want == shown, f"validator frames {want}, plugin frames {shown}"
PY
echo "simulate_fault: $RULE fires (companions: $companions), and the plugin shows it on the same frames"
