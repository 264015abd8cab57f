#!/usr/bin/env bash
# cli_usage.sh SRC BUILD: the command line and the configuration as a user types them:
# rule IDs in any case, "did you mean" for mistyped commands, options, keys and IDs,
# standard input given twice, --version of a subcommand, an [[axis]] missing an address, names
# that need CSV quoting, `rules --explain`, and the exit statuses the commands share (an
# unwritable output 2, no servo 4).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

expect() {  # expect RC ARGS...: runs ncservo ARGS, checks its exit status; output in out and err
  local expected=$1
  shift
  set +e
  "$NCSERVO" "$@" >"$WORK/out" 2>"$WORK/err"
  local rc=$?
  set -e
  [ "$rc" = "$expected" ] || fail "ncservo $*: exit $rc, expected $expected; stderr: $(head -3 "$WORK/err")"
}
says() {  # says FILE TEXT: FILE (out or err) holds TEXT
  grep -qF -- "$2" "$WORK/$1" || fail "expected '$2' in $1: $(head -5 "$WORK/$1")"
}

"$NCSERVO" simulate --axes 2 --duration 1 -o "$WORK/clean.pcap" --layout-config "$WORK/layout.toml" 2>/dev/null
"$NCSERVO" simulate --axes 2 --duration 2.5 --fault SE-001 --fault MSG-001:1 -o "$WORK/faults.pcap" 2>/dev/null

# Rule IDs in any case: on the command line and in the configuration.
expect 1 validate "$WORK/faults.pcap"
expect 0 validate --disable se-001,Msg-001 "$WORK/faults.pcap"
expect 0 validate --severity se-001=info --disable msg-001 "$WORK/faults.pcap"
printf '[rules]\ndisable = ["se-001", "msg-001"]\n' >"$WORK/lower.toml"
expect 0 validate --config "$WORK/lower.toml" "$WORK/faults.pcap"
printf '[rules]\nseverity = { "se-001" = "info", "Msg-001" = "info" }\n' >"$WORK/severity.toml"
expect 0 validate --config "$WORK/severity.toml" "$WORK/faults.pcap"

# "Did you mean": commands, options, rule IDs, configuration keys and timeouts.
expect 2 valdate "$WORK/clean.pcap"
says err "unknown command 'valdate'; did you mean 'validate'?"
expect 2 validate --formt json "$WORK/clean.pcap"
says err "unknown option '--formt'; did you mean '--format'?"
expect 2 decode --layuot "$WORK/clean.pcap"
says err "unknown option '--layuot'; did you mean '--layout'?"
expect 2 validate --disable MSG-01 "$WORK/clean.pcap"
says err "unknown rule ID 'MSG-01' (see \`ncservo rules\`); did you mean 'MSG-001'?"
expect 2 validate --severity ec-02=error "$WORK/clean.pcap"
says err "did you mean 'EC-002'?"
expect 2 validate --timeout drive_respons=30 "$WORK/clean.pcap"
says err "did you mean 'drive_response'?"
printf 'telegram_failure_limt = 3\n' >"$WORK/typo.toml"
expect 2 validate --config "$WORK/typo.toml" "$WORK/clean.pcap"
says err "typo.toml:1: key 'telegram_failure_limt': unknown key; did you mean 'telegram_failure_limit'?"
printf '[rules]\ndisable = ["SE-01"]\n' >"$WORK/id.toml"
expect 2 validate --config "$WORK/id.toml" "$WORK/clean.pcap"
says err "id.toml:2: key 'rules.disable'"
says err "did you mean 'SE-001'?"

# Standard input can be read once.
expect 2 validate - - <"$WORK/clean.pcap"
says err "standard input (-) can be read only once"
expect 0 validate - <"$WORK/clean.pcap"

# --version of a subcommand prints the version, as `ncservo --version` does.
expect 0 --version
version=$(cat "$WORK/out")
[[ "$version" == "ncservo "* ]] || fail "ncservo --version: $version"
for command in decode validate rules fields simulate; do
  expect 0 "$command" --version
  [ "$(cat "$WORK/out")" = "$version" ] || fail "$command --version: $(cat "$WORK/out" "$WORK/err")"
done

# An [[axis]] needs both addresses: the error names the file, the line and the key.
printf 'servo_ready_mode = 0\n\n[[axis]]\nname = "X"\noutputs = 0x10000\n' >"$WORK/no-inputs.toml"
expect 2 validate --config "$WORK/no-inputs.toml" "$WORK/clean.pcap"
says err "no-inputs.toml:3: key 'axis[0].inputs': missing"
printf '[[axis]]\nname = "X"\ninputs = 0x10014\n' >"$WORK/no-outputs.toml"
expect 2 decode --config "$WORK/no-outputs.toml" "$WORK/clean.pcap"
says err "no-outputs.toml:1: key 'axis[0].outputs': missing"
printf '[[axis]]\nname = "Y"\nstation = 0x3EA\nsm_inputs = 0x1180\n' >"$WORK/no-sm.toml"
expect 2 validate --config "$WORK/no-sm.toml" "$WORK/clean.pcap"
says err "no-sm.toml:1: key 'axis[0].sm_outputs': missing"

# CSV (RFC 4180): names holding a comma, a quote or a line break are quoted and read back whole.
sed -e "s/name = 'axis0'/name = \"X, left\"/" -e "s/name = 'axis1'/name = \"the \\\\\"Y\\\\\"\\\\nspindle\"/" \
  "$WORK/layout.toml" >"$WORK/names.toml"
expect 0 decode --config "$WORK/names.toml" "$WORK/clean.pcap"
python3 - "$WORK/out" <<'PY' || fail "decode CSV with quoted names"
import csv, sys
with open(sys.argv[1], newline="") as f:
    rows = list(csv.reader(f))
header = rows[0]
assert all(len(r) == len(header) for r in rows), "a row with another number of columns"
names = {r[header.index("name")] for r in rows[1:]}
assert names == {"X, left", 'the "Y"\nspindle'}, names
PY

# rules --explain: one rule in full, ID in any case; a typo is named, an unknown ID is exit 2.
expect 0 rules --explain se-003
for text in "SE-003 not-disabled" "severity:    error" "party:       drive" \
  "timeout:     drive_response, default 20 ms" "reads:       scw.se, ssw.servo_en" \
  "docs/protocol.md §2 SE" "ncservo.rule.not_disabled" "docs/rules.md"; do
  says out "$text"
done
expect 0 rules --explain COM-004
says out "COM-004 frame-not-returned"
if grep -q "timeout:" "$WORK/out"; then fail "COM-004 has no timeout: $(cat "$WORK/out")"; fi
expect 2 rules --explain SE-03
says err "did you mean 'SE-003'?"
expect 2 rules --explain XX-999
says err "unknown rule ID 'XX-999'"

# Every command that reads a capture takes the layout options from one declaration: the same
# help lines everywhere (docs/cli.md).
layout_help() {  # layout_help COMMAND: its help's lines for --config, --no-default-layout, --eni
  "$NCSERVO" "$1" --help | grep -E -- '^ +--(config|no-default-layout|eni)\b'
}
layout_help decode >"$WORK/layout-decode.txt"
[ "$(wc -l <"$WORK/layout-decode.txt")" -eq 3 ] || fail "decode --help: $(cat "$WORK/layout-decode.txt")"
# monitor's --metrics and --mqtt are checked before anything is captured (the interface need not
# exist): a usage error naming what is wrong.
expect 2 monitor -i no-such-if0 --metrics 127.0.0.1:http
grep -q "expected \[ADDRESS:\]PORT" "$WORK/err" || fail "--metrics: $(cat "$WORK/err")"
expect 2 monitor -i no-such-if0 --mqtt http://broker/m
grep -q "expected mqtt://HOST\[:PORT\]/PREFIX" "$WORK/err" || fail "--mqtt: $(cat "$WORK/err")"
expect 2 monitor -i no-such-if0 --mqtt mqtt://broker
grep -q "no topic prefix" "$WORK/err" || fail "--mqtt without prefix: $(cat "$WORK/err")"
expect 2 monitor -i no-such-if0 --mqtt mqtt://broker/m --mqtt-ca "$WORK/clean.pcap"
grep -q "need mqtts://" "$WORK/err" || fail "--mqtt-ca with mqtt://: $(cat "$WORK/err")"
expect 2 monitor -i no-such-if0 --mqtt mqtts://broker/m --mqtt-cert "$WORK/clean.pcap"
grep -q "go together" "$WORK/err" || fail "--mqtt-cert alone: $(cat "$WORK/err")"
expect 2 merge
expect 3 merge "$WORK/clean.pcap"
grep -q "clean.pcap: not JSON" "$WORK/err" || fail "merge of a capture: $(cat "$WORK/err")"

for command in validate annotate monitor diff; do
  layout_help "$command" | diff "$WORK/layout-decode.txt" - >/dev/null ||
    fail "$command --help: the layout options differ from decode's"
done
# Every enumerated option says the choices and the closest one (commands.hpp oneOf).
expect 2 validate --fail-on warn "$WORK/clean.pcap"
says err "--fail-on: warn is not one of {error,warning,info,never}; did you mean 'warning'?"
expect 2 validate --format jsn "$WORK/clean.pcap"
says err "did you mean 'json'?"
expect 2 decode --timestamps prob "$WORK/clean.pcap"
says err "did you mean 'probe'?"
expect 2 simulate --scenario fault -o "$WORK/x.pcap"
says err "did you mean 'faults'?"

# When each rule is reported, as the code does it: COM-002 one cycle after the gap (docs/rules.md).
expect 0 rules --explain COM-002
says out "reported:    at the next master copy after the gap, one cycle after it"
expect 0 rules --explain SE-001
says out "reported:    on the frame where the condition begins"
# MSG-001 and the layout inference share one range (docs/protocol.md §5): 6-9 listed, no meaning.
expect 0 rules --explain MSG-001
says out "a message code outside 0-5 (6-9 are listed without a meaning)"

# decode --axis naming no axis: the usage error alone, no CSV header before it.
expect 2 decode --axis 7 "$WORK/clean.pcap"
says err "--axis 7: no such axis"
[ ! -s "$WORK/out" ] || fail "decode --axis 7 wrote: $(head -2 "$WORK/out")"
expect 0 decode --axis 1 "$WORK/clean.pcap"
head -1 "$WORK/out" | grep -q "^frame,time,axis,name," || fail "decode --axis 1: no header"

# No servo in a capture (EtherCAT-free frames): decode and annotate exit 4 as validate does, and
# annotate says so.
python3 - "$WORK/none.pcap" <<'PY'
import struct, sys
frame = bytes.fromhex("ffffffffffff0002030405060806") + bytes(46)  # an ARP-sized frame, no EtherCAT
with open(sys.argv[1], "wb") as f:
    f.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1))
    for i in range(3):
        f.write(struct.pack("<IIII", 1, i * 1000, len(frame), len(frame)) + frame)
PY
expect 4 validate "$WORK/none.pcap"
expect 4 decode "$WORK/none.pcap"
says err "no EtherCAT frame in the capture"
expect 4 annotate "$WORK/none.pcap" "$WORK/none-annotated.pcapng"
says err "NO SERVO:"
[ -s "$WORK/none-annotated.pcapng" ] || fail "annotate wrote no copy"
expect 0 annotate "$WORK/clean.pcap" "$WORK/clean-annotated.pcapng"

# An output that cannot be written is a usage error in every command (docs/cli.md#exit-status).
nowhere="$WORK/no/such/dir"
expect 2 validate -o "$nowhere/r.txt" "$WORK/clean.pcap"
expect 2 decode -o "$nowhere/r.csv" "$WORK/clean.pcap"
expect 2 annotate "$WORK/clean.pcap" "$nowhere/a.pcapng"
says err "cannot write"
expect 2 simulate --duration 1 -o "$nowhere/s.pcap"
says err "cannot write"
expect 3 annotate "$WORK/missing.pcap" "$WORK/a.pcapng"
echo "cli_usage: IDs in any case, did-you-mean, stdin once, --version, axis addresses, CSV, --explain, layout options, exit statuses that agree"
