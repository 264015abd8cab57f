#!/usr/bin/env bash
# incidents_plugin.sh SRC BUILD CAPTURE...: on each bundled capture with drive faults, `validate`'s
# JSON incidents and tshark with the plugin (`ncservo.incident`, docs/incidents.md) name the same
# frames, axes and causes, and each incident's evidence frames are the plugin's
# `ncservo.incident.evidence` (the captures must hold at least one incident).
SRC=$1 BUILD=$2
shift 2
source "$SRC/tests/integration/lib.sh"
for capture in "$@"; do
  path=$SRC/captures/$capture
  "$NCSERVO" validate --format json --fail-on never "$path" >"$WORK/report.json" ||
    fail "$capture: validate exit $?"
  "$TSHARK" "$PLUGIN" -2 -r "$path" -Y ncservo.incident -T pdml >"$WORK/plugin.pdml" 2>"$WORK/err.txt" ||
    fail "$capture: tshark exit $?: $(head -3 "$WORK/err.txt")"
  python3 - "$capture" "$WORK/report.json" "$WORK/plugin.pdml" <<'PY' || exit 1
import json, sys
import xml.etree.ElementTree as ET
capture, report, pdml = sys.argv[1:]
cli = []
for i in json.load(open(report))["captures"][0]["incidents"]:
    cli.append((i["frame"], i["axis"], i["cause"]["id"], i["cause"]["text"],
                [e["frame"] for e in i["evidence"]]))
plugin = []
for packet in ET.parse(pdml).getroot().iter("packet"):
    frame = None
    for proto in packet.iter("proto"):
        if proto.get("name") == "frame":
            for f in proto.iter("field"):
                if f.get("name") == "frame.number":
                    frame = int(f.get("show"))
        if proto.get("name") != "ncservo":
            continue
        axis = None
        for f in proto.iter("field"):
            if f.get("name") == "ncservo.axis" and axis is None:
                axis = int(f.get("show"))
            if f.get("name") == "ncservo.incident":
                cause, _, text = f.get("show").partition(": ")
                evidence = [int(e.get("show")) for e in f.iter("field")
                            if e.get("name") == "ncservo.incident.evidence"]
                plugin.append((frame, axis, cause, text, evidence))
if not cli:
    print(f"FAIL: {capture}: validate lists no incident", file=sys.stderr)
    sys.exit(1)
# Each incident of validate is one of the plugin's: the same frame, cause and text, in the layer of
# its axis (a bus incident is in the frame's first layer), with the same evidence frames.
left = list(plugin)
for c in cli:
    match = [p for p in left if p[0] == c[0] and p[2:4] == c[2:4] and (c[1] is None or p[1] == c[1])]
    if not match:
        print(f"FAIL: {capture}: frame {c[0]} axis {c[1]} {c[2]} not in the plugin: {plugin}", file=sys.stderr)
        sys.exit(1)
    if match[0][4] != c[4]:
        print(f"FAIL: {capture}: frame {c[0]}: evidence {c[4]} in validate, {match[0][4]} in the plugin", file=sys.stderr)
        sys.exit(1)
    left.remove(match[0])
if left:
    print(f"FAIL: {capture}: the plugin has incidents validate has not: {left}", file=sys.stderr)
    sys.exit(1)
print(f"{capture}: {len(cli)} incidents, the same in validate and the plugin: "
      + "; ".join(f"frame {c[0]} axis {c[1]} {c[2]}" for c in cli))
PY
done
echo "incidents_plugin: validate and the plugin agree"
