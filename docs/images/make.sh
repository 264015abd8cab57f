#!/usr/bin/env bash
# Makes the README's pictures from captures/faults-4axis.pcap, so they can be made again when the
# output changes:
#   docs/images/html-report.png  the HTML report (validate --format html) in headless Chromium
#   docs/images/gtkwave.png      GTKWave under Xvfb with decode --format vcd's save file, zoomed
#                                onto the first illegal-enable finding (SE-001)
#   docs/images/drive-messages.png  an axis card of the HTML report with the drive's emergency
#                                beside the errors read from SEW, and the link the ESC counters
#                                name (the generator's capture, docs/drive-messages.md)
# and beside each the text it shows (html-report.txt, gtkwave.txt, from docs/images/shown.sh), which
# tests/integration/readme_pictures.sh compares with today's output.
# Needs Debian's chromium, gtkwave, xvfb and imagemagick (.ci/setup installs them).
#
# Usage: docs/images/make.sh [BUILD_DIR]     (default: the repository's build/)
set -euo pipefail
export LC_ALL=C

root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$root/build}
ncservo=$build/validator/ncservo
images=$root/docs/images
cd "$root"
capture=captures/faults-4axis.pcap  # relative: the page shows the path as given
for tool in chromium gtkwave xvfb-run import; do
  command -v "$tool" >/dev/null || { echo "make.sh: $tool not found (.ci/setup installs it)" >&2; exit 1; }
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The report, its first rows and timelines (the page is taller: the window shows the top).
"$ncservo" validate --format html -o "$work/faults.html" "$capture" >/dev/null 2>&1 || [ $? = 1 ]
chromium --headless=new --no-sandbox --disable-gpu --hide-scrollbars \
  --host-resolver-rules='MAP * ~NOTFOUND' --window-size=1280,1600 \
  --screenshot="$work/html.png" "file://$work/faults.html" >/dev/null 2>&1
convert "$work/html.png" -strip "$images/html-report.png"
"$images/shown.sh" html-report.png "$build" >"$images/html-report.txt"

# The first SE-001 of the JSON report: its axis, and its time in ns since the capture's start
# (the VCD's time 0 is the first frame, as the report's `time`).
"$ncservo" validate --format json -o "$work/faults.json" "$capture" >/dev/null 2>&1 || [ $? = 1 ]
read -r axis at_ns < <(python3 - "$work/faults.json" <<'PY'
import json, sys
capture = json.load(open(sys.argv[1]))["captures"][0]
f = next(f for f in capture["findings"] if f["rule"] == "SE-001")
print(f["axis_name"], round(f["time"] * 1e9))
PY
)
"$ncservo" decode --format vcd --axis "$axis" "$capture" -o "$work/faults.vcd" 2>/dev/null
# GTKWave shows 10 ms around the finding (wide enough for the rule ID on the findings trace),
# draws, takes the screen with ImageMagick and quits.
cat >"$work/shot.tcl" <<TCL
gtkwave::setZoomRangeTimes $((at_ns - 5000000)) $((at_ns + 5000000))
gtkwave::setMarker $at_ns
update
after 2000
update
exec import -window root "$work/gtkwave.png"
gtkwave::/File/Quit
TCL
(cd "$work" && timeout 120 xvfb-run -a -s "-screen 0 1280x800x24" \
  gtkwave -6 faults.gtkw -S shot.tcl >/dev/null 2>&1) || true
[ -s "$work/gtkwave.png" ] || { echo "make.sh: GTKWave gave no screenshot" >&2; exit 1; }
convert "$work/gtkwave.png" -trim +repage -strip "$images/gtkwave.png"  # the window, not the screen
"$images/shown.sh" gtkwave.png "$build" >"$images/gtkwave.txt"
# What the drives said (docs/drive-messages.md): the first axis card with the drive's own words,
# and the links the ESC counters name under it, each cut out of the page in Chromium.
NCSERVO_SHOWN_PAGE="$work/drive-messages.html" "$images/shown.sh" drive-messages.png "$build" \
  >"$images/drive-messages.txt"
/usr/bin/python3 - "$work/drive-messages.html" "$work/drive-messages.png" "$root/tests/tools" <<'PY'
import pathlib, subprocess, sys
sys.path.insert(0, sys.argv[3])
from check_html_report import browser  # Debian's chromium and chromedriver, no network
page, out = pathlib.Path(sys.argv[1]), sys.argv[2]
driver = browser()
try:
    driver.set_window_size(1400, 1000)
    driver.get(page.resolve().as_uri())
    card = driver.execute_script(
        "return [...document.querySelectorAll('div.axis')].find(d => d.querySelector('table.said'))")
    links = driver.execute_script("return document.querySelector('table.links')")
    card.screenshot(out + ".card.png")
    links.screenshot(out + ".links.png")
finally:
    driver.quit()
subprocess.run(["convert", "-background", "white", out + ".card.png", out + ".links.png",
                "-gravity", "west", "-splice", "12x0", "-append", "-strip", out], check=True)
PY
cp "$work/drive-messages.png" "$images/drive-messages.png"
echo "make.sh: wrote $images/html-report.png, $images/gtkwave.png ($axis, SE-001 at $at_ns ns)" \
  "and $images/drive-messages.png"
