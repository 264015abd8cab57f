#!/usr/bin/env bash
# layout_sources.sh SRC BUILD
# The layout sources (docs/protocol.md §9) and their precedence, through the real CLI and tshark:
# for a simulated set-up with start-up and I/O terminals sharing the LRW (interleaved), the layout
# learned from the start-up, the ENI the simulator writes, the configuration it writes and the one
# `decode --layout` prints all give the same axes; a configuration beats an ENI, an ENI beats the
# start-up, the start-up beats the default layout; a bad ENI is a usage error naming its line.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
"$NCSERVO" simulate --axes 3 --io-slaves 3 --layout interleaved --duration 1.5 --seed 11 \
  -o "$WORK/io.pcap" --layout-config "$WORK/sim.toml" --eni "$WORK/sim.xml" 2>/dev/null
"$NCSERVO" simulate --axes 3 --io-slaves 3 --layout interleaved --duration 1.5 --seed 11 \
  --no-startup -o "$WORK/nostartup.pcap" 2>/dev/null
chmod a+r "$WORK"/*
"$NCSERVO" decode --layout "$WORK/io.pcap" >"$WORK/decoded.txt"
grep -q "^# layout source: startup, 3 axes" "$WORK/decoded.txt" || fail "decode --layout: $(head -1 "$WORK/decoded.txt")"
grep -v '^#' "$WORK/decoded.txt" >"$WORK/learned.toml"

layout() { # layout ARGS...: "source axis:station:outputs:inputs ..." of validate's JSON report
  "$NCSERVO" validate --format json --fail-on never --allow-empty "$@" | python3 -c '
import json, sys
c = json.load(sys.stdin)["captures"][0]
axes = [":".join(str(a.get(k)) for k in ("station", "outputs", "inputs")) for a in c["layout"]["axes"]]
print(c["layout"]["source"], " ".join(axes), len(c["findings"]))'
}
learned=$(layout "$WORK/io.pcap")
want_axes=${learned#startup }
[ "${learned%% *}" = startup ] || fail "no configuration: source ${learned%% *}, expected startup"
# every row: arguments | the source the report must name
rows=(
  "--config $WORK/sim.toml|config"
  "--config $WORK/learned.toml|config"
  "--eni $WORK/sim.xml|eni"
  "--eni $WORK/sim.xml --config $WORK/sim.toml|config"
)
for row in "${rows[@]}"; do
  IFS='|' read -r args source <<<"$row"
  read -r -a argv <<<"$args"
  got=$(layout "${argv[@]}" "$WORK/io.pcap")
  [ "$got" = "$source $want_axes" ] || fail "$args: '$got', expected '$source $want_axes'"
done
# Without the start-up in the capture: the ENI places the axes, or the inference finds the same
# addresses (it cannot know the stations).
got=$(layout --eni "$WORK/sim.xml" "$WORK/nostartup.pcap")
[ "$got" = "eni $want_axes" ] || fail "no start-up, ENI: '$got'"
got=$(layout "$WORK/nostartup.pcap")
want_inferred=$(sed -E 's/(^| )[^: ]+:/\1None:/g' <<<"$want_axes")
[ "$got" = "inferred $want_inferred" ] || fail "no start-up, nothing given: '$got', expected 'inferred $want_inferred'"
# The plugin: the same from its ENI preference, and from the start-up with no preference.
for args in "-o ncservo.eni:$WORK/sim.xml -r $WORK/nostartup.pcap" "-r $WORK/io.pcap"; do
  read -r -a argv <<<"$args"
  "$TSHARK" "$PLUGIN" -2 "${argv[@]}" -Y ncservo.sew -T fields -e ncservo.axis >"$WORK/axes.txt" 2>"$WORK/err.txt" ||
    fail "tshark $args: exit $?: $(cat "$WORK/err.txt")"
  [ ! -s "$WORK/err.txt" ] || fail "tshark $args: $(head -3 "$WORK/err.txt")"
  grep -qx "0,1,2" "$WORK/axes.txt" || fail "tshark $args: axes $(sort -u "$WORK/axes.txt" | head -3 | tr '\n' ' ')"
done
# A bad ENI ends with exit 2 and names the file and the line; one without servos says so.
printf '<EtherCATConfig><Config>\n<Slave>\n</Config>' >"$WORK/bad.xml"
set +e
"$NCSERVO" validate --eni "$WORK/bad.xml" "$WORK/io.pcap" >/dev/null 2>"$WORK/err.txt"
rc=$?
set -e
[ $rc = 2 ] || fail "bad ENI: exit $rc"
grep -q "^ncservo: $WORK/bad.xml:3: not well-formed XML" "$WORK/err.txt" || fail "bad ENI: $(cat "$WORK/err.txt")"
printf '<EtherCATConfig><Config><Slave><Info><Name>IO</Name></Info></Slave></Config></EtherCATConfig>' >"$WORK/io.xml"
set +e
"$NCSERVO" decode --eni "$WORK/io.xml" "$WORK/io.pcap" >/dev/null 2>"$WORK/err.txt"
rc=$?
set -e
[ $rc = 2 ] || fail "ENI without servos: exit $rc"
grep -q "no servo of this protocol (10-byte outputs, 40-byte inputs) among its 1 slaves" "$WORK/err.txt" ||
  fail "ENI without servos: $(cat "$WORK/err.txt")"
echo "layout_sources: start-up, ENI and configurations agree ($want_axes); precedence holds"
