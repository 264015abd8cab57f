#!/usr/bin/env bash
# Prints the text a README picture shows, from today's output, one line each, without drawing:
#   html-report.png        the page's verdict line, its findings table and its timelines' captions
#                          and rows, from the data inside the page (validate --format html)
#   gtkwave.png            the finding the marker is on and the signals of the save file
#   wireshark-finding.png  the findings of the frames listed and frame 1203's axes (tshark -2 with
#                          the plugin)
#   drive-messages.png     the axis cards with what the drive said beside the errors read from SEW,
#                          and the links under the bus, from the data inside the page (validate
#                          --format html on the generator's capture with a drive's emergency and a
#                          bad link; NCSERVO_SHOWN_PAGE=FILE keeps the page for make.sh)
# make.sh and make-wireshark.sh keep it beside each picture (PICTURE.txt) when they draw it;
# tests/integration/readme_pictures.sh makes it again and compares, so a picture whose text the
# tool no longer prints fails the tests until it is drawn again.
#
# Usage: docs/images/shown.sh PICTURE [BUILD_DIR]     (default: the repository's build/)
set -euo pipefail
export LC_ALL=C

picture=${1:?usage: shown.sh PICTURE [BUILD_DIR]}
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${2:-$root/build}
ncservo=$(realpath -m "$build/validator/ncservo")  # absolute: some cases run in a folder of their own
cd "$root"
capture=captures/faults-4axis.pcap  # relative: the page shows the path as given (make.sh)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The first SE-001 of the JSON report: its axis, frame and time in ns since the capture's start
# (make.sh zooms GTKWave onto it).
first_se001() {
  "$ncservo" validate --format json -o "$work/faults.json" "$capture" >/dev/null 2>&1 || [ $? = 1 ]
  python3 - "$work/faults.json" <<'PY'
import json, sys
capture = json.load(open(sys.argv[1]))["captures"][0]
f = next(f for f in capture["findings"] if f["rule"] == "SE-001")
print(f["axis_name"], round(f["time"] * 1e9), f["frame"])
PY
}

case $picture in
  html-report.png)
    "$ncservo" validate --format html -o "$work/faults.html" "$capture" >/dev/null 2>&1 || [ $? = 1 ]
    python3 - "$work/faults.html" <<'PY'
import json, re, sys
page = open(sys.argv[1], encoding="utf-8").read()
data = json.loads(re.search(r'<script type="application/json" id="ncservo-data">(.*?)</script>',
                            page, re.S).group(1))
for capture in data["captures"]:
    c = capture["counts"]
    print(f"{capture['path']}: {capture['verdict'].upper()} {c['error']} errors, {c['warning']} warnings,"
          f" {c['info']} info; {capture['frames']} frames, {capture['cycles']} cycles;"
          f" layout: {capture['layout_source']}")
    for n, (rule, severity, axis, frame, _, message) in enumerate(capture["findings"]):
        print(f"finding #{n + 1} {severity} {rule} {axis} frame {frame}: {message}")
    for t in capture["timelines"]:
        rule, _, axis, frame, _, _ = capture["findings"][t["finding"]]
        rows = ", ".join(trace["label"] for trace in t["traces"])
        print(f"timeline #{t['finding'] + 1} {rule} {data['rules'][rule]['slug']}, {axis},"
              f" frame {frame}: {rows}")
PY
    ;;
  gtkwave.png)
    read -r axis at_ns frame < <(first_se001)
    echo "marker: SE-001 $axis frame $frame at $at_ns ns"
    (cd "$work" && "$ncservo" decode --format vcd --axis "$axis" "$root/$capture" -o faults.vcd 2>/dev/null)
    # The save file's signals, as GTKWave lists them.
    grep -v '^[[*@-]' "$work/faults.gtkw" | sed 's/^/signal: /'
    ;;
  wireshark-finding.png)
    tshark=$root/tests/tools/tshark-with-plugin.sh
    plugin=$build/plugin/ncservo.so
    # The plugin's own items (not Wireshark's layout, which changes with its version): the
    # findings of the listed frames, then each axis layer of frame 1203.
    "$tshark" "$plugin" -2 -r "$capture" -Y ncservo.finding -T fields -E occurrence=a \
      -E aggregator='|' -e frame.number -e ncservo.finding | sed 's/^/list: /'
    "$tshark" "$plugin" -2 -r "$capture" -Y 'frame.number == 1203' -T fields -E occurrence=a \
      -E aggregator='|' -e frame.number -e ncservo.axis_name -e ncservo.state -e ncservo.scw \
      -e ncservo.ssw -e ncservo.sew -e ncservo.finding -e ncservo.since_frame | sed 's/^/Frame /'
    ;;
  drive-messages.png)
    # Deterministic: the independent generator's capture, its layout naming the stations.
    (cd "$work" && python3 "$root/tests/tools/gen_capture.py" --axes 3 --cycles 3000 --seed 5 \
      --inject MBX-002 --incident link-fault --layout-config layout.toml -o drive-messages.pcap &&
      { "$ncservo" validate --config layout.toml --format html -o page.html drive-messages.pcap \
        >/dev/null 2>&1 || [ $? = 1 ]; })
    [ -z "${NCSERVO_SHOWN_PAGE:-}" ] || cp "$work/page.html" "$NCSERVO_SHOWN_PAGE"
    python3 - "$work/page.html" <<'PY'
import json, re, sys
page = open(sys.argv[1], encoding="utf-8").read()
data = json.loads(re.search(r'<script type="application/json" id="ncservo-data">(.*?)</script>',
                            page, re.S).group(1))
for capture in data["captures"]:
    for axis in capture["axes"]:
        if not axis["said"]:
            continue
        for time, error, code, frame in axis["errors"]:
            print(f"{axis['name']} error {error} {code} frame {frame}")
        for frame, message, request in axis["said"]:
            print(f"{axis['name']} said at frame {frame}: {message}")
    for frame, link, errors in capture["bus_said"]["links"]:
        print(f"link at frame {frame}: {link}: {errors} errors")
PY
    ;;
  *)
    echo "shown.sh: no picture $picture (html-report.png, gtkwave.png, wireshark-finding.png," \
      "drive-messages.png)" >&2
    exit 2
    ;;
esac
