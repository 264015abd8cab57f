#!/usr/bin/env bash
# Runs tshark with a given ncservo.so loaded next to the stock EtherCAT plugin.
# Usage: tshark-with-plugin.sh PLUGIN_SO|none [tshark args...]
#   PLUGIN_SO = none runs the same tshark with only the stock plugins (a baseline).
# Wireshark ignores personal plugin folders and WIRESHARK_PLUGIN_DIR when run as root
# (PROTOCOL.md §10), so as root tshark runs as the unprivileged user nobody.
set -euo pipefail
plugin=$1
shift
stock_dir=$(dirname "$(find /usr/lib/*/wireshark/plugins/4.0/epan -name ethercat.so | head -n1)")
key=$(echo "$plugin" | md5sum | cut -c1-12)
dir=${NCSERVO_PLUGIN_STAGE:-/tmp}/ncservo-wsplug-$key
mkdir -p "$dir/4.0/epan"
for so in "$stock_dir"/*.so; do ln -sf "$so" "$dir/4.0/epan/"; done
if [ "$plugin" != none ]; then
  # Copy then rename, so a tshark starting in parallel never loads a half-written plugin.
  tmp=$(mktemp "$dir/4.0/epan/.ncservo.XXXXXX")
  cp -f "$plugin" "$tmp"
  chmod a+r "$tmp"
  mv -f "$tmp" "$dir/4.0/epan/ncservo.so"
fi
chmod -R a+rX "$dir"
if [ "$(id -u)" = 0 ]; then
  exec setpriv --reuid=65534 --regid=65534 --clear-groups \
    env HOME=/nonexistent WIRESHARK_PLUGIN_DIR="$dir" tshark "$@"
fi
exec env WIRESHARK_PLUGIN_DIR="$dir" tshark "$@"
