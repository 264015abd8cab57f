#!/usr/bin/env bash
# validate_injected.sh SRC BUILD RULE [generator options...]
# A violation of RULE injected by the independent generator is reported by `ncservo validate` with
# the right rule, axis and a frame inside the violation's window, nothing else of any severity
# but the companions the generator names; and tshark with the plugin shows the finding
# (ncservo.rule.<slug>) on exactly the frames the validator reports for that rule, at the rule's
# severity and group (lib.sh rule_frames).
SRC=$1 BUILD=$2 RULE=$3
shift 3
source "$SRC/tests/integration/lib.sh"
# A rule judged on the axis whose drive said it needs the layout's stations: the generator's
# layout file names them, for the validator and the plugin alike.
layout=() plugin_layout=()
if python3 "$GEN" --list-station-rules | grep -x "$RULE" >/dev/null; then
  layout=(--config "$WORK/layout.toml") plugin_layout=(-o "ncservo.config:$WORK/layout.toml")
fi
python3 "$GEN" --axes 3 --cycles 1500 --inject "$RULE" "$@" -o "$WORK/capture.pcap" \
  --findings "$WORK/expected.json" --layout-config "$WORK/layout.toml"
chmod a+r "$WORK/capture.pcap" "$WORK/layout.toml"
set +e
"$NCSERVO" validate --format json "${layout[@]}" "$WORK/capture.pcap" >"$WORK/report.json" \
  2>"$WORK/err.txt"
rc=$?
set -e
[ $rc = 0 ] || [ $rc = 1 ] || fail "validate exit $rc: $(cat "$WORK/err.txt")"
python3 "$SRC/tests/tools/check_findings.py" "$WORK/report.json" "$WORK/expected.json" ||
  fail "$RULE: findings differ from the injection"

rule_frames "$RULE" "$WORK/capture.pcap" "$WORK/plugin.txt" "${plugin_layout[@]}"
python3 - "$WORK/report.json" "$WORK/plugin.txt" "$RULE" <<'PY' || fail "$RULE: plugin and validator disagree"
import json, sys
findings = json.load(open(sys.argv[1]))["captures"][0]["findings"]
want = sorted({f["frame"] for f in findings if f["rule"] == sys.argv[3]})
shown = sorted({int(l) for l in open(sys.argv[2]) if l.strip()})
assert want, "the validator reported nothing"
assert want == shown, f"validator frames {want}, plugin frames {shown}"
PY
echo "validate_injected: $RULE reported as injected, and by the plugin on the same frames"
