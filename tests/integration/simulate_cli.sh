#!/usr/bin/env bash
# simulate_cli.sh SRC BUILD
# `ncservo simulate` as users meet it: bad options end with exit 2 and a message that says what
# is wrong; an unwritable output with exit 2 (a usage error, as in every command); the output is a pure function of the options;
# `-o -` streams into `validate -`; pcapng carries nanosecond timestamps.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
# expected exit | expected message (grep -F) | arguments
cases=(
  "2|give the capture to write with -o FILE|simulate"
  "2|--axes 33: from 1 to 32|simulate --axes 33 -o $WORK/x.pcap"
  "2|--cycle-us 100: from 125 to 10000|simulate --cycle-us 100 -o $WORK/x.pcap"
  "2|--fault XX-001: no rule 'XX-001'|simulate --fault XX-001 -o $WORK/x.pcap"
  "2|expected RULE[@SECONDS][:AXIS]|simulate --fault SE-001@soon -o $WORK/x.pcap"
  "2|ZP-001 needs an incremental axis (odd index)|simulate --fault ZP-001:2 -o $WORK/x.pcap"
  "2|ZP-003 needs an absolute axis (even index)|simulate --fault ZP-003:1 -o $WORK/x.pcap"
  "2|axis 7 does not exist (--axes 4)|simulate --fault SE-003:7 -o $WORK/x.pcap"
  "2|COM-002 concerns the whole bus; no :axis|simulate --fault COM-002:1 -o $WORK/x.pcap"
  "2|ESM-001 happens in the start-up; give no @time|simulate --fault ESM-001@1 -o $WORK/x.pcap"
  "2|ESM-004 happens in the start-up|simulate --no-startup --fault ESM-004 -o $WORK/x.pcap"
  "2|outside the quiet part of the run (0.65 s to 1.34 s)|simulate --fault SE-001@0.1 -o $WORK/x.pcap"
  "2|the run is too short for a fault; use --duration 2.5|simulate --duration 1.2 --fault SE-001 -o $WORK/x.pcap"
  "2|--scenario faults needs at least 4 axes|simulate --scenario faults --axes 3 -o $WORK/x.pcap"
  "2|--jitter-us 300: from 0 to a fifth of the cycle (200)|simulate --jitter-us 300 -o $WORK/x.pcap"
  "2|--incidents-truth needs --scenario incidents|simulate --incidents-truth $WORK/t.json -o $WORK/x.pcap"
  "2|--scenario incidents takes no --fault|simulate --scenario incidents --fault SE-001 -o $WORK/x.pcap"
  "2|--scenario incidents needs --duration 6 or more|simulate --scenario incidents --duration 5 -o $WORK/x.pcap"
  "2|$WORK/no/such/dir/x.pcap: cannot write|simulate -o $WORK/no/such/dir/x.pcap"
  "0|wrote 3004 frames to $WORK/ok.pcap|simulate --duration 1.5 -o $WORK/ok.pcap"
)
for row in "${cases[@]}"; do
  IFS='|' read -r want message args <<<"$row"
  read -r -a argv <<<"$args"
  set +e
  "$NCSERVO" "${argv[@]}" >"$WORK/out.txt" 2>"$WORK/err.txt"
  rc=$?
  set -e
  [ "$rc" = "$want" ] || fail "ncservo $args: exit $rc, expected $want: $(cat "$WORK/err.txt")"
  grep -qF -- "$message" "$WORK/err.txt" || fail "ncservo $args: no '$message' in: $(cat "$WORK/err.txt")"
done

# A pure function of the options: the same bytes twice, other bytes for another seed.
opts=(simulate --axes 3 --duration 2.5 --fault SE-001 --jitter-us 50 --loss 0.01)
"$NCSERVO" "${opts[@]}" --seed 4 -o "$WORK/a.pcap" 2>/dev/null
"$NCSERVO" "${opts[@]}" --seed 4 -o "$WORK/b.pcap" 2>/dev/null
"$NCSERVO" "${opts[@]}" --seed 5 -o "$WORK/c.pcap" 2>/dev/null
cmp -s "$WORK/a.pcap" "$WORK/b.pcap" || fail "the same options gave different captures"
! cmp -s "$WORK/a.pcap" "$WORK/c.pcap" || fail "another seed gave the same capture"

# Standard output into standard input: the same report as through a file.
"$NCSERVO" simulate --axes 2 --duration 2.5 --fault FLT-001 -o - |
  "$NCSERVO" validate --format jsonl --fail-on never - >"$WORK/piped.jsonl"
"$NCSERVO" simulate --axes 2 --duration 2.5 --fault FLT-001 -o "$WORK/f.pcap" 2>/dev/null
"$NCSERVO" validate --format jsonl --fail-on never "$WORK/f.pcap" >"$WORK/file.jsonl"
diff <(grep -o '"rule":"[^"]*".*"frame":[0-9]*' "$WORK/piped.jsonl") \
  <(grep -o '"rule":"[^"]*".*"frame":[0-9]*' "$WORK/file.jsonl") >/dev/null ||
  fail "piped and file reports differ"
grep -q '"rule":"FLT-001"' "$WORK/piped.jsonl" || fail "the piped capture lost its FLT-001"

# pcapng: nanosecond resolution, readable by tshark; pcap: microseconds.
"$NCSERVO" simulate --axes 2 --duration 1.2 -o "$WORK/n.pcapng" 2>/dev/null
capinfos "$WORK/n.pcapng" >"$WORK/capinfos.txt"
grep -q "File type: *Wireshark/... - pcapng" "$WORK/capinfos.txt" || fail "not a pcapng: $(head -3 "$WORK/capinfos.txt")"
grep -q "File timestamp precision: *nanoseconds (9)" "$WORK/capinfos.txt" ||
  fail "pcapng timestamps are not in nanoseconds: $(grep -i precision "$WORK/capinfos.txt")"
capinfos "$WORK/ok.pcap" | grep -q "File timestamp precision: *microseconds (6)" || fail "pcap is not in microseconds"
cmp -s <(tshark -r "$WORK/n.pcapng" -T fields -e frame.len -e frame.time_epoch 2>/dev/null) \
  <("$NCSERVO" simulate --axes 2 --duration 1.2 --format pcap -o - | tshark -r - -T fields -e frame.len -e frame.time_epoch 2>/dev/null) ||
  fail "pcap and pcapng of the same run hold different frames or times"
echo "simulate_cli: ${#cases[@]} option cases, deterministic, streams, pcap and pcapng"
