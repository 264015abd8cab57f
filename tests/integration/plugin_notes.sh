#!/usr/bin/env bash
# plugin_notes.sh SRC BUILD: what the CLI warns of a layout the plugin says as expert info on the
# capture's first decoded frame (docs/plugin.md#preferences): a configured layout two bytes off
# (ncservo.layout_misfit, in a later pass: tshark -2, the GUI), and a configuration file with a
# typo (ncservo.preference_error, in one pass and two).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
cd "$WORK"
"$NCSERVO" simulate --axes 2 --seed 4 -o cap.pcap --layout-config ok.toml 2>/dev/null
# Every address two bytes on.
python3 - <<'PY'
import re
text = open("ok.toml").read()
open("off2.toml", "w").write(re.sub(r"(outputs|inputs) = (0x[0-9A-Fa-f]+)",
                                    lambda m: f"{m[1]} = {int(m[2], 16) + 2:#010x}", text))
PY
printf 'telegram_failure_limt = 3\n' >typo.toml
chmod a+r cap.pcap ok.toml off2.toml typo.toml

"$NCSERVO" validate --config off2.toml --fail-on never cap.pcap >cli.txt 2>&1 || true
grep -q 'layout does not fit' cli.txt || fail "the CLI does not warn of off2.toml: $(head -3 cli.txt)"

# notes OUT CONFIG [tshark options]: the frames with a note, and its text.
notes() {
  local out=$1 config=$2
  shift 2
  "$TSHARK" "$PLUGIN" -r cap.pcap -o "ncservo.config:$WORK/$config" "$@" \
    -Y 'ncservo.layout_misfit || ncservo.preference_error' -T fields -e frame.number \
    -e _ws.expert.message >"$out" 2>tshark.err || fail "tshark on $config exited $?: $(cat tshark.err)"
}

notes misfit.tsv off2.toml -2
[ "$(wc -l <misfit.tsv)" = 1 ] || fail "off2.toml: $(wc -l <misfit.tsv) frames with a note, expected 1: $(cat misfit.tsv)"
# (Wireshark cuts an expert message at 240 bytes.)
grep -q 'layout does not fit: axis0: the data at .* does not look like this protocol' misfit.tsv ||
  fail "off2.toml: the note is not the CLI's warning: $(cat misfit.tsv)"
"$TSHARK" "$PLUGIN" -2 -r cap.pcap -o "ncservo.config:$WORK/off2.toml" -q -z expert >expert.txt 2>/dev/null ||
  fail "tshark -z expert exited $?"
grep -q 'layout does not fit' expert.txt || fail "-z expert: no misfit: $(head -20 expert.txt)"
notes fit.tsv ok.toml -2
[ ! -s fit.tsv ] || fail "ok.toml: a note on a layout that fits: $(cat fit.tsv)"
echo "ok a layout two bytes off: its warning as expert info"

for passes in "" -2; do
  notes typo$passes.tsv typo.toml $passes
  [ "$(wc -l <typo$passes.tsv)" = 1 ] || fail "typo.toml ${passes:-one pass}: $(wc -l <typo$passes.tsv) frames with a note"
  grep -q "preference not used: .*typo.toml:1: key 'telegram_failure_limt': unknown key; did you mean 'telegram_failure_limit'" \
    typo$passes.tsv || fail "typo.toml ${passes:-one pass}: $(cat typo$passes.tsv)"
  grep -q "telegram_failure_limt" tshark.err || fail "typo.toml: no longer said on standard error"
done
echo "plugin_notes: a misfit layout and a mistyped configuration file, as expert info on the first frame"
