#!/usr/bin/env bash
# plugin_personal_folder.sh SRC BUILD
# A normal user installs the plugin as docs/plugin.md says: into the personal plugin folder that
# `tshark -G folders` names (for this Wireshark's major.minor, plus epan/). `tshark -G plugins`
# then lists ncservo.so from there, beside the stock EtherCAT dissector, and the plugin decodes.
# As root the user is nobody with a home of its own, since Wireshark ignores personal plugins
# for root.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

home=$WORK/home
mkdir -p "$home"
as_user=(env -i PATH=/usr/bin:/bin HOME="$home")
# An ASan + UBSan plugin needs the sanitizer runtime preloaded, as tshark-with-plugin.sh does.
if [ -f "$PLUGIN.preload" ]; then
  mkdir -p "$WORK/no-extcap"
  as_user+=(LD_PRELOAD="$(cat "$PLUGIN.preload")" WIRESHARK_EXTCAP_DIR="$WORK/no-extcap"
    ASAN_OPTIONS=detect_leaks=0:abort_on_error=1:halt_on_error=1
    UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1)
fi
if [ "$(id -u)" = 0 ]; then
  chown 65534:65534 "$home"
  chmod a+rx "$WORK"
  as_user=(setpriv --reuid=65534 --regid=65534 --clear-groups "${as_user[@]}")
fi
personal=$("${as_user[@]}" tshark -G folders 2>/dev/null | sed -n 's/^Personal Plugins:[[:space:]]*//p')
case $personal in
"$home"/*) ;;
*) fail "tshark -G folders: personal plugins in '$personal', not under $home" ;;
esac
version=$(basename "$personal")
"${as_user[@]}" mkdir -p "$personal/epan"
"${as_user[@]}" cp "$PLUGIN" "$personal/epan/ncservo.so"
"${as_user[@]}" tshark -G plugins >"$WORK/plugins.txt" 2>"$WORK/err.txt" || fail "tshark -G plugins: $(cat "$WORK/err.txt")"
grep -qP "^ncservo\.so *\t[^\t]*\tdissector\t\Q$personal/epan/ncservo.so\E$" "$WORK/plugins.txt" ||
  fail "ncservo.so not listed from $personal/epan: $(grep -i ncservo "$WORK/plugins.txt")"
grep -qP '^ethercat\.so *\t' "$WORK/plugins.txt" || fail "the stock EtherCAT plugin is not listed"
"${as_user[@]}" tshark -r - -Y 'ncservo.axis == 1' -T fields -e ncservo.axis_name \
  <"$SRC/captures/faults-4axis.pcap" >"$WORK/decoded.txt" 2>"$WORK/err.txt" || fail "tshark -r: $(cat "$WORK/err.txt")"
grep -q axis1 "$WORK/decoded.txt" || fail "the plugin from the personal folder decoded no axis 1: $(head -c 200 "$WORK/decoded.txt")"
echo "plugin_personal_folder: tshark $version lists and runs ncservo.so from $personal/epan"
