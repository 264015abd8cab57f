# Shared helpers for the integration tests (sourced). Expects BUILD and SRC set by the caller.
set -euo pipefail
TSHARK="$SRC/tests/tools/tshark-with-plugin.sh"
GEN="$SRC/tests/tools/gen_capture.py"
CHECK="$SRC/tests/tools/check_fields.py"
NCSERVO="$BUILD/validator/ncservo"
PLUGIN="$BUILD/plugin/ncservo.so"
WORK=$(mktemp -d)
chmod 755 "$WORK"  # tshark runs as nobody when the tests run as root
trap 'rm -rf "$WORK"' EXIT

ALL_FIELDS=(ncservo.ssp ncservo.scw ncservo.ext_code ncservo.actpos ncservo.ssw ncservo.sew
            ncservo.msg_code ncservo.msg_data ncservo.ext_data1 ncservo.ext_data2
            ncservo.ext_data3 ncservo.ext_data4)

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

# skip REASON: what the test needs is not on this machine. Says why and exits 77 (ctest: Skipped);
# under CI (CI set and not empty) nothing may be missing, so it fails instead.
skip() {
  [ -z "${CI:-}" ] || fail "$* (CI is set: a test may not skip)"
  echo "SKIPPED: $*"
  exit 77
}

# require_program PROGRAM...: each is on PATH, else skip naming the first one missing.
require_program() {
  local program
  for program in "$@"; do
    command -v "$program" >/dev/null || skip "$program not installed (.ci/setup installs it)"
  done
}

# require_path PATH WHAT [DONE]: PATH exists, else skip saying WHAT it is (and DONE: what ran).
require_path() {
  [ -e "$1" ] || skip "no $2 at $1${3:+; $3}"
}

# The real captures from other people's hardware, beside the repository (never copied into it).
REAL_CAPTURES="$(cd "$SRC/.." && pwd)/shared/captures/real"

# tshark_fields CAPTURE OUT [tshark options...]: every PDO field, one column each.
tshark_fields() {
  local capture=$1 out=$2
  shift 2
  local args=()
  for f in "${ALL_FIELDS[@]}"; do args+=(-e "$f"); done
  "$TSHARK" "$PLUGIN" -2 -r "$capture" "$@" -T fields -E occurrence=a -E separator=/t -E aggregator=, \
    -e frame.number "${args[@]}" >"$out" 2>"$WORK/tshark.err" || fail "tshark exited $? on $capture: $(cat "$WORK/tshark.err")"
  if [ -s "$WORK/tshark.err" ]; then fail "tshark printed on stderr: $(head -5 "$WORK/tshark.err")"; fi
}

fields_csv() {
  local IFS=,
  echo "${ALL_FIELDS[*]}"
}

# veth_pair PREFIX: a veth pair, `$host` here and `$peer` in the network namespace `$ns` (names
# from PREFIX and this shell's pid), both up; removed with $WORK when the script exits.
veth_pair() {
  ns=ncservo-$1-$$
  host=$1$$a peer=$1$$b
  trap 'ip netns del "$ns" 2>/dev/null || true; ip link del "$host" 2>/dev/null || true; rm -rf "$WORK"' EXIT
  ip netns add "$ns"
  ip link add "$host" type veth peer name "$peer" netns "$ns"
  ip link set "$host" up
  ip -n "$ns" link set "$peer" up
}

# rule_frames RULE CAPTURE OUT [tshark options...]: the frames on which tshark with the plugin shows
# RULE, one a line, into OUT; fails unless each of RULE's expert items has the severity and group
# docs/plugin.md gives its rule's severity and party, written here by hand, not read from the plugin.
rule_frames() {
  local rule=$1 capture=$2 out=$3 slug severity party
  shift 3
  read -r slug severity party < <("$NCSERVO" rules | awk -v id="$rule" '$1 == id { print $2, $3, $4 }')
  [ -n "$slug" ] || fail "no rule $rule"
  "$TSHARK" "$PLUGIN" "$@" -2 -r "$capture" -Y "ncservo.rule.${slug//-/_}" -T fields \
    -E occurrence=a -E aggregator='|' -e frame.number -e _ws.expert.message \
    -e _ws.expert.severity -e _ws.expert.group >"$WORK/expert.tsv" 2>"$WORK/tshark.err" ||
    fail "tshark exit $?: $(cat "$WORK/tshark.err")"
  [ ! -s "$WORK/tshark.err" ] || fail "tshark stderr: $(head -3 "$WORK/tshark.err")"
  python3 - "$WORK/expert.tsv" "$rule $slug" "$severity" "$party" >"$out" <<'PY' || fail "$rule: the plugin's expert info is not the rule's severity and group"
import sys
tsv, message, severity, party = sys.argv[1:]
# epan/proto.h: PI_ERROR, PI_WARN, PI_NOTE; PI_SEQUENCE for the bus, PI_PROTOCOL for NC and drive.
want = ({"error": 0x00800000, "warning": 0x00600000, "info": 0x00400000}[severity],
        0x02000000 if party == "bus" else 0x09000000)
for line in open(tsv):
    frame, messages, severities, groups = line.rstrip("\n").split("\t")
    print(frame)
    for m, s, g in zip(messages.split("|"), severities.split("|"), groups.split("|")):
        if m == message and (int(s), int(g)) != want:
            sys.exit(f"frame {frame}: {m} at severity {int(s):#x}, group {int(g):#x}; "
                     f"a rule of severity {severity}, party {party} is at {want[0]:#x}, group {want[1]:#x}")
PY
}

# free_port: a TCP port on 127.0.0.1 nobody listens on now (the system's pick).
free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

# replay_into_peer CAPTURE: tcpreplay CAPTURE into `$peer` in `$ns` (veth_pair), on time on a busy
# machine: under a real-time policy where allowed, with tcpreplay's nanosleep() timer (the
# default one busy-waits and is then throttled; monitor_live.sh says why at length).
replay_into_peer() {
  local realtime="chrt -f 50"
  $realtime true 2>/dev/null || realtime=""
  ip netns exec "$ns" $realtime tcpreplay -q --preload-pcap --timer=nano -i "$peer" "$1" >/dev/null
}

# wait_for TRIES COMMAND...: COMMAND until it succeeds, every 0.2 s, TRIES times at most.
wait_for() {
  local tries=$1
  shift
  for ((i = 0; i < tries; i++)); do
    "$@" >/dev/null 2>&1 && return 0
    sleep 0.2
  done
  return 1
}
