#!/usr/bin/env bash
# plugin_prefs.sh SRC BUILD: the plugin's preferences: a Servo_Ready_Mode that is
# not auto, 0 or 1 is reported, not taken silently; rule IDs in the configuration file in any
# case; `tshark -G defaultprefs` describes every preference, pointing only into the repository.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
capture="$SRC/captures/commissioning-4axis.pcap"

ts() {  # ts ARGS...: tshark with the plugin on the bundled capture; its stderr in ts.err
  "$TSHARK" "$PLUGIN" -r "$capture" -c 1 "$@" >/dev/null 2>"$WORK/ts.err" ||
    fail "tshark $* exited $?: $(head -3 "$WORK/ts.err")"
}

ts -o ncservo.servo_ready_mode:banana
grep -qF "ncservo.servo_ready_mode: 'banana' is not auto, 0 or 1" "$WORK/ts.err" ||
  fail "banana was taken silently: $(cat "$WORK/ts.err")"
for mode in auto AUTO 0 1 "Servo_Ready_Mode 1" "Inferred from the capture"; do
  ts -o "ncservo.servo_ready_mode:$mode"
  [ ! -s "$WORK/ts.err" ] || fail "servo_ready_mode:$mode: $(cat "$WORK/ts.err")"
done

printf '[rules]\ndisable = ["se-001"]\nseverity = { "msg-001" = "info" }\n' >"$WORK/lower.toml"
chmod a+r "$WORK/lower.toml"
ts -o "ncservo.config:$WORK/lower.toml"
[ ! -s "$WORK/ts.err" ] || fail "lower-case rule IDs in ncservo.config: $(cat "$WORK/ts.err")"
printf '[rules]\ndisable = ["SE-01"]\n' >"$WORK/typo.toml"
chmod a+r "$WORK/typo.toml"
ts -o "ncservo.config:$WORK/typo.toml"
grep -qF "did you mean 'SE-001'?" "$WORK/ts.err" || fail "typo in ncservo.config: $(cat "$WORK/ts.err")"

"$TSHARK" "$PLUGIN" -G defaultprefs >"$WORK/prefs.txt" 2>/dev/null
python3 - "$WORK/prefs.txt" <<'PY' || fail "tshark -G defaultprefs"
import re, sys
lines = open(sys.argv[1]).read().split("\n")
prefs = {}
for i, line in enumerate(lines):
    m = re.match(r"#(ncservo\.\w+):", line)
    if m:
        block = []
        j = i - 1
        while j >= 0 and lines[j].startswith("# "):
            block.insert(0, lines[j][2:])
            j -= 1
        prefs[m.group(1)] = " ".join(block)
want = {"ncservo.config", "ncservo.eni", "ncservo.servo_ready_mode", "ncservo.default_layout"}
assert set(prefs) == want, sorted(prefs)
for name, text in prefs.items():
    assert len(text) > 40, (name, text)
    assert not re.search(r"RULES\.md|PROTOCOL\.md|INTERFACES\.md|\.\./shared", text), (name, text)
assert "auto" in prefs["ncservo.servo_ready_mode"] and "0 or 1" in prefs["ncservo.servo_ready_mode"]
PY
echo "plugin_prefs: a bad Servo_Ready_Mode is reported, IDs in any case, every preference described"
