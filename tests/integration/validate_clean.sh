#!/usr/bin/env bash
# validate_clean.sh SRC BUILD
# Conforming sessions from the independent generator — with a drive fault the drive handles
# correctly — give no finding at all, at cycle times from 125 µs to 10 ms, in both ready modes,
# with 1 to 29 axes, over every framing; and the fault is in the axis's error history.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
while read -r name args; do
  [ -n "$name" ] || continue
  # shellcheck disable=SC2086
  python3 "$GEN" $args -o "$WORK/$name.pcap"
  "$NCSERVO" validate --format json "$WORK/$name.pcap" >"$WORK/$name.json" || fail "$name: exit $?"
  python3 - "$WORK/$name.json" "$name" <<'PY' || fail "$name: findings in a clean session"
import json, sys
c = json.load(open(sys.argv[1]))["captures"][0]
assert c["findings"] == [], c["findings"][:3]
assert c["layout"]["source"] == "inferred"
history = [e["code"] for a in c["axes"] for e in a["error_history"]]
if sys.argv[2] != "master_only":  # no inputs: no state, no history
    assert "E09" in history, history  # the following error the drive reported and cleared
PY
done <<'LIST'
1ms_4axes --axes 4 --cycles 2000
125us_2axes --axes 2 --cycle-us 125 --cycles 16000
10ms_3axes --axes 3 --cycle-us 10000 --cycles 400
ready_mode_1 --axes 4 --cycles 2000 --ready-mode 1
29_axes --axes 29 --cycles 1200
vlan_pcapng_ns --axes 4 --encap vlan --format pcapng --nanosecond
udp --axes 2 --encap udp --cycles 1000
returned_only --axes 4 --copies returned --cycles 1000
master_only --axes 4 --copies master --cycles 1000
LIST
echo "validate_clean: no finding in conforming sessions"
