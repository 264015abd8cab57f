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
key = lambda i: (i[0], i[2], i[3])
if sorted(map(key, cli)) != sorted(map(key, plugin)):
    print(f"FAIL: {capture}: incidents differ\n validate: {sorted(map(key, cli))}\n plugin:   {sorted(map(key, plugin))}", file=sys.stderr)
    sys.exit(1)
for c in cli:
    p = [p for p in plugin if key(p) == key(c)][0]
    if c[1] is not None and p[1] != c[1]:
        print(f"FAIL: {capture}: frame {c[0]}: axis {c[1]} in validate, {p[1]} in the plugin", file=sys.stderr)
        sys.exit(1)
    if p[4] != c[4]:
        print(f"FAIL: {capture}: frame {c[0]}: evidence {c[4]} in validate, {p[4]} in the plugin", file=sys.stderr)
        sys.exit(1)
print(f"{capture}: {len(cli)} incidents, the same in validate and the plugin: "
      + "; ".join(f"frame {c[0]} axis {c[1]} {c[2]}" for c in cli))
PY
done
echo "incidents_plugin: validate and the plugin agree"
