#!/usr/bin/env bash
# Makes the README's screenshot: Wireshark with the plugin on captures/faults-4axis.pcap, showing
# the frames with a finding, frame 1203 selected (FLT-001 on axis 2) and that axis's tree expanded.
# Needs Xvfb, the Wireshark GUI, xdotool and ImageMagick (Debian: xvfb wireshark xdotool
# imagemagick). Not run in CI: it drives the GUI by screen positions and keystrokes, and its
# pixels change with Wireshark's and the fonts' versions; look at the image after making it.
# Beside the picture, the text it shows (wireshark-finding.txt, from docs/images/shown.sh), which
# tests/integration/readme_pictures.sh compares with today's output.
# Usage: docs/images/make-wireshark.sh [BUILD_DIR] [OUT.png]
#   default BUILD_DIR build, OUT docs/images/wireshark-finding.png
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$root/build}
out=$(realpath -m "${2:-$root/docs/images/wireshark-finding.png}")
plugin=$build/plugin/ncservo.so
capture=$root/captures/faults-4axis.pcap
frame=1203
# Top rows of the details pane above axis 2: Frame, Ethernet II, EtherCAT frame header,
# EtherCAT datagram(s), NC-Servo axis 0, NC-Servo axis 1.
rows_above=6
width=1280 height=960
upper_pane=230        # the packet list's height
details_top=$((95 + upper_pane))  # menu, tool and filter bars, then the list and the splitter
display=:${NCSERVO_SHOT_DISPLAY:-77}

for tool in Xvfb wireshark xdotool import; do
  command -v "$tool" >/dev/null || { echo "make-wireshark: $tool not found" >&2; exit 2; }
done
[ -f "$plugin" ] || { echo "make-wireshark: no $plugin (build first)" >&2; exit 2; }

tmp=$(mktemp -d)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  rm -rf "$tmp"
}
trap cleanup EXIT

# A home of its own: the plugin in its personal plugin folder, the window's size and the
# packet list's height in the recent files, no other preferences.
home=$tmp/home
plugins=$home/.local/lib/wireshark/plugins/$(tshark -v | sed -n '1s/^TShark (Wireshark) \([0-9]*\.[0-9]*\).*/\1/p')/epan
mkdir -p "$plugins" "$home/.config/wireshark"
cp "$plugin" "$plugins/"
cp "$capture" "$home/"
printf 'gui.geometry_main_x: 0\ngui.geometry_main_y: 0\ngui.geometry_main_width: %s\ngui.geometry_main_height: %s\ngui.geometry_main_maximized: FALSE\n' \
  "$width" "$height" >"$home/.config/wireshark/recent_common"
printf 'gui.geometry_main_upper_pane: %s\n' "$upper_pane" >"$home/.config/wireshark/recent"
chmod -R a+rwX "$tmp"

Xvfb "$display" -screen 0 "${width}x${height}x24" -ac -nolisten tcp >"$tmp/xvfb.log" 2>&1 &
pids+=($!)
sleep 1
export DISPLAY=$display
# Wireshark run as root ignores personal plugins: as root, run it as the user nobody.
as_user=()
if [ "$(id -u)" = 0 ]; then
  chown -R 65534:65534 "$home"
  as_user=(setpriv --reuid=65534 --regid=65534 --clear-groups)
fi
"${as_user[@]}" env HOME="$home" DISPLAY="$display" wireshark -r "$home/$(basename "$capture")" \
  -Y ncservo.finding -g "$frame" -o gui.layout_content_3:NONE >"$tmp/wireshark.log" 2>&1 &
pids+=($!)

window=$(timeout 60 xdotool search --sync --name "$(basename "$capture")" | head -n1) || {
  echo "make-wireshark: no Wireshark window; its messages:" >&2
  cat "$tmp/wireshark.log" >&2
  exit 1
}
sleep 4  # the capture read and the frame selected
# Axis 2's layer: the first row of the details pane, down to the axis, every subtree expanded.
xdotool mousemove --sync 200 $((details_top + 10)) click 1
xdotool key Home
for _ in $(seq "$rows_above"); do xdotool key Down; done
xdotool key shift+Right
sleep 1
mkdir -p "$(dirname "$out")"
import -window root "$out"
"$root/docs/images/shown.sh" wireshark-finding.png "$build" >"${out%.png}.txt"
echo "make-wireshark: wrote $out (window $window); look at it before committing it"
