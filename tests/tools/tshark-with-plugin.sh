#!/usr/bin/env bash
# Runs tshark with a given ncservo.so loaded next to the stock EtherCAT plugin.
# Usage: tshark-with-plugin.sh PLUGIN_SO|none [tshark args...]
#   PLUGIN_SO = none runs the same tshark with only the stock plugins (a baseline).
# Wireshark ignores personal plugin folders and WIRESHARK_PLUGIN_DIR when run as root
# (docs/plugin.md), so as root tshark runs as the unprivileged user nobody.
set -euo pipefail
plugin=$1
shift
key=$(echo "$plugin" | md5sum | cut -c1-12)
dir=${NCSERVO_PLUGIN_STAGE:-/tmp}/ncservo-wsplug-$key
mkdir -p "$dir"
# The stock plugins are in the installed tshark's global folder, named for its major.minor
# (plugins/4.4): asked of tshark once per staging folder.
if [ ! -s "$dir/.global-plugins" ]; then
  global=$(tshark -G folders 2>/dev/null | sed -n 's/^Global Plugins:[[:space:]]*//p')
  [ -d "$global/epan" ] || { echo "tshark-with-plugin.sh: no global plugin folder from 'tshark -G folders'" >&2; exit 2; }
  tmp=$(mktemp "$dir/.global-plugins.XXXXXX")
  echo "$global" >"$tmp"
  mv -f "$tmp" "$dir/.global-plugins"
fi
global=$(cat "$dir/.global-plugins")
version_dir=$dir/$(basename "$global")
mkdir -p "$version_dir/epan"
for so in "$global"/epan/*.so; do ln -sf "$so" "$version_dir/epan/"; done
if [ "$plugin" != none ]; then
  # Copy then rename, so a tshark starting in parallel never loads a half-written plugin.
  tmp=$(mktemp "$version_dir/epan/.ncservo.XXXXXX")
  cp -f "$plugin" "$tmp"
  chmod a+r "$tmp"
  mv -f "$tmp" "$version_dir/epan/ncservo.so"
fi
# Not recursive: another run may be renaming its copy of the plugin in there right now.
chmod a+rx "$dir" "$version_dir" "$version_dir/epan"
# A plugin built with ASan + UBSan (NCSERVO_SANITIZE) needs the sanitizer runtime preloaded into
# the stock tshark; its build leaves the runtime's path beside it. Any report aborts tshark.
# Leaks are not checked: tshark's own allocations at exit would drown ours. The extcap helpers
# tshark starts (e.g. for -G defaultprefs) would inherit the preload, and androiddump then
# deadlocks at exit (libp11-kit's freelocale on the setlocale lock): they get an empty folder.
sanitizer_env=()
if [ "$plugin" != none ] && [ -f "$plugin.preload" ]; then
  no_extcap=${NCSERVO_PLUGIN_STAGE:-/tmp}/ncservo-no-extcap
  mkdir -p "$no_extcap"
  chmod a+rx "$no_extcap"
  sanitizer_env=(LD_PRELOAD="$(cat "$plugin.preload")" WIRESHARK_EXTCAP_DIR="$no_extcap"
    ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=0:abort_on_error=1:halt_on_error=1}"
    UBSAN_OPTIONS="${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}")
fi
if [ "$(id -u)" = 0 ]; then
  exec setpriv --reuid=65534 --regid=65534 --clear-groups \
    env HOME=/nonexistent WIRESHARK_PLUGIN_DIR="$dir" "${sanitizer_env[@]}" tshark "$@"
fi
exec env WIRESHARK_PLUGIN_DIR="$dir" "${sanitizer_env[@]}" tshark "$@"
