#!/usr/bin/env bash
# monitor_mqtt.sh SRC BUILD: `ncservo monitor --mqtt` publishing to a real Mosquitto broker
# (Debian's mosquitto, started here with persistence on a free port) while tcpreplay replays a
# simulated capture with faults into a veth pair in a network namespace; the broker is stopped
# and started again in the middle of the replay. A subscriber (mosquitto_sub -q 1 -v, a session
# of its own that the broker keeps) receives every finding the monitor reported and every incident
# `ncservo validate` finds in the frames the monitor captured (its flight recording), nothing
# lost; a message received twice (QoS 1 after the restart) is the same object, told by its
# fingerprint and frame. The status topic says "online", then "offline" (retained) at the end,
# and the broker's last will says it for a monitor killed outright. mqtts:// with a CA and a
# client certificate reaches a broker that requires one, and without the certificate does not.
# What the drives and ESCs said is published on its topics as validate reports it.
# With no broker at all, a queue of --mqtt-queue messages keeps that many and counts the rest.
# Needs root, tcpreplay, mosquitto and openssl: otherwise exit 77 with the reason (under CI:
# fails).
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

[ "$(id -u)" = 0 ] || skip "needs root (veth pair, network namespace)"
require_program tcpreplay ip mosquitto mosquitto_sub openssl

veth_pair ncsq
cd "$WORK"
"$NCSERVO" simulate --scenario faults --cycle-us 4000 -o faults.pcap 2>/dev/null
port=$(free_port)
mkdir -p db
cat >mosquitto.conf <<CONF
listener $port 127.0.0.1
allow_anonymous true
persistence true
persistence_location $WORK/db/
user root
CONF
broker=""
start_broker() {
  mosquitto -c mosquitto.conf >>broker.log 2>&1 &
  broker=$!
  wait_for 50 mosquitto_sub -p "$port" -t probe -W 1 -C 1 -E || fail "mosquitto did not start: $(tail -3 broker.log)"
}
sub=""
trap 'kill "$sub" "$broker" 2>/dev/null || true; ip netns del "$ns" 2>/dev/null || true; ip link del "$host" 2>/dev/null || true; rm -rf "$WORK"' EXIT
start_broker
prefix=plant/cell1
# A session the broker keeps (-c, a fixed id): what comes while it is away waits for it.
mosquitto_sub -h 127.0.0.1 -p "$port" -q 1 -v -c -i ncservo-test-sub -t "$prefix/#" >received.txt 2>sub.err &
sub=$!
subscribed() {
  mosquitto_pub -p "$port" -q 1 -t "$prefix/probe" -m hello && grep -q "^$prefix/probe hello" received.txt
}
wait_for 50 subscribed || fail "the subscriber never got a message: $(cat sub.err)"

rm -rf rec && mkdir rec
"$NCSERVO" monitor -i "$host" --format jsonl --mqtt "mqtt://127.0.0.1:$port/$prefix" \
  --mqtt-client-id ncservo-test --record rec --record-window 60 >live.jsonl 2>live.err &
monitor=$!
wait_for 50 grep -q "connected to" live.err || fail "the monitor did not connect: $(cat live.err)"

replay_into_peer faults.pcap &
replay=$!
sleep 1.5
kill -TERM "$broker"
wait "$broker" || true
echo "broker stopped at $(date +%T.%N)"
sleep 1
start_broker
echo "broker started again at $(date +%T.%N)"
wait "$replay" || fail "tcpreplay failed"
sleep 1
kill -INT "$monitor"
rc=0
wait "$monitor" || rc=$?
[ "$rc" = 1 ] || fail "monitor: exit $rc (findings of errors: 1): $(cat live.err)"
grep -q "connection lost" live.err || fail "the monitor never saw the broker go: $(cat live.err)"
[ "$(grep -c "connected to" live.err)" -ge 2 ] || fail "the monitor did not connect again: $(cat live.err)"
# Findings came while the broker was away: they waited in the queue.
grep "connected to" live.err | tail -1 | grep -q "([1-9][0-9]* messages waiting)" ||
  fail "nothing waited for the broker, so the test proved nothing: $(cat live.err)"
! grep -q "messages not acknowledged\|messages dropped" live.err || fail "messages left behind: $(cat live.err)"
grep -q "frames captured; dropped: 0 by the kernel" live.err || fail "the capture dropped frames: $(cat live.err)"
sleep 1
kill -INT "$sub"
wait "$sub" || true

recordings=(rec/*.pcapng)
[ "${#recordings[@]}" = 1 ] || fail "a 60 s window over the run: ${#recordings[@]} recordings"
"$NCSERVO" validate --format json --fail-on never "${recordings[0]}" >rec.json
"$NCSERVO" validate --format json --fail-on never faults.pcap >file.json
python3 - received.txt live.jsonl rec.json file.json "$prefix" <<'PY' || fail "the subscriber's messages differ"
import collections, json, sys
received, live, rec, filejson, prefix = sys.argv[1:]
capture = json.load(open(rec))["captures"][0]
assert capture["frames"] == json.load(open(filejson))["captures"][0]["frames"], "the monitor missed frames"
by_topic = collections.defaultdict(list)
for line in open(received):
    topic, _, payload = line.rstrip("\n").partition(" ")
    by_topic[topic].append(payload)
def unique(topic, key):
    seen, dups = {}, 0
    for payload in by_topic[prefix + "/" + topic]:
        j = json.loads(payload)
        k = key(j)
        if k in seen:
            assert seen[k] == j, f"{topic} {k} twice, differing: {seen[k]} / {j}"
            dups += 1
        seen[k] = j
    return seen, dups
findings, fdups = unique("finding", lambda j: (j["fingerprint"], j["frame"]))
incidents, idups = unique("incident", lambda j: j["incident"]["fingerprint"])
live_findings = {(j["fingerprint"], j["frame"]) for j in map(json.loads, open(live)) if "rule" in j}
assert len(live_findings) > 5, "the faults capture has findings"
missing = live_findings - set(findings)
assert not missing, f"{len(missing)} findings lost: {sorted(missing)[:5]}"
assert set(findings) == live_findings, f"findings never reported: {set(findings) - live_findings}"
report = {(f["fingerprint"], f["frame"]) for f in capture["findings"]}
assert set(findings) == report, f"validate of the recording: {sorted(report ^ set(findings))[:5]}"
want = {i["fingerprint"] for i in capture["incidents"]}
assert want, "the faults capture has incidents"
assert set(incidents) == want, f"incidents: lost {want - set(incidents)}, extra {set(incidents) - want}"
status = by_topic[prefix + "/status"]
assert status and status[0] == "online" and status[-1] == "offline", f"status: {status}"
print(f"ok {len(findings)} findings and {len(incidents)} incidents received, none lost "
      f"({fdups + idups} received twice after the restart, the same objects); status {status}")
PY

# What the drives and ESCs said (docs/drive-messages.md): the independent generator's SDO answers,
# aborts and a bad link, each published on its topic as the JSON Lines object validate gives for
# the monitor's recording.
python3 "$SRC/tests/tools/gen_capture.py" --axes 3 --cycles 3000 --seed 5 --inject MBX-003 \
  --incident link-fault -o said.pcap >/dev/null || fail "gen_capture.py exited $?"
mosquitto_sub -h 127.0.0.1 -p "$port" -q 1 -v -t "$prefix/drive-message" -t "$prefix/link-fault" \
  -t "$prefix/said-probe" >said.txt 2>said-sub.err &
sub=$!
said_subscribed() {
  mosquitto_pub -p "$port" -q 1 -t "$prefix/said-probe" -m hello && grep -q "said-probe hello" said.txt
}
wait_for 50 said_subscribed || fail "the subscriber never got a message: $(cat said-sub.err)"
rm -rf said-rec && mkdir said-rec
"$NCSERVO" monitor -i "$host" --mqtt "mqtt://127.0.0.1:$port/$prefix" --mqtt-client-id ncservo-said \
  --record said-rec --record-window 60 >/dev/null 2>said.err &
monitor=$!
wait_for 50 grep -q "connected to" said.err || fail "the monitor did not connect: $(cat said.err)"
replay_into_peer said.pcap || fail "tcpreplay failed"
sleep 1
kill -INT "$monitor"
wait "$monitor" || true
sleep 0.5
kill -INT "$sub"
wait "$sub" || true
said_recordings=(said-rec/*.pcapng)
"$NCSERVO" validate --format jsonl --fail-on never "${said_recordings[0]}" >said-rec.jsonl
python3 - said.txt said-rec.jsonl "$prefix" <<'PY' || fail "the drive messages and link faults published differ"
import json, sys
received, rec, prefix = sys.argv[1:]
got = {"drive_message": [], "link_fault": []}
for line in open(received):
    topic, _, payload = line.rstrip("\n").partition(" ")
    if topic.endswith("/said-probe"):
        continue
    j = json.loads(payload)
    key = "drive_message" if topic == prefix + "/drive-message" else "link_fault"
    got[key].append(j[key])
want = {"drive_message": [], "link_fault": []}
for line in open(rec):
    j = json.loads(line)
    for key in want:
        if key in j:
            want[key].append(j[key])
assert len(want["drive_message"]) >= 3 and want["link_fault"], f"the capture was to hold them: {want}"
for key in want:
    assert got[key] == want[key], f"{key}: published {got[key][:3]}, validate of the recording {want[key][:3]}"
print(f"ok {len(got['drive_message'])} drive messages and {len(got['link_fault'])} link faults published"
      " as validate reports them")
PY

# The last will: a monitor killed outright is "offline" by the broker's word.
"$NCSERVO" monitor -i "$host" --mqtt "mqtt://127.0.0.1:$port/$prefix" --mqtt-client-id ncservo-will \
  >/dev/null 2>will.err &
monitor=$!
wait_for 50 grep -q "connected to" will.err || fail "no connection: $(cat will.err)"
[ "$(mosquitto_sub -p "$port" -t "$prefix/status" -C 1 -W 3)" = online ] || fail "not online"
kill -KILL "$monitor"
wait "$monitor" 2>/dev/null || true
last=""
for _ in 1 2 3 4 5 6 7 8 9 10; do
  last=$(mosquitto_sub -p "$port" -t "$prefix/status" -C 1 -W 3)
  [ "$last" = offline ] && break
  sleep 0.5
done
[ "$last" = offline ] || fail "after kill -9 the status says '$last', not the will's offline"
echo "ok the last will says offline for a monitor killed outright"

# A broker that never comes: the queue keeps --mqtt-queue messages, drops the oldest past that
# and says how many, and the end says what was never acknowledged.
nobody=$(free_port)
"$NCSERVO" monitor -i "$host" --format jsonl --mqtt "mqtt://127.0.0.1:$nobody/$prefix" \
  --mqtt-queue 5 --mqtt-flush 0 >bounded.jsonl 2>bounded.err &
monitor=$!
sleep 1
replay_into_peer faults.pcap || fail "tcpreplay failed"
sleep 0.5
kill -INT "$monitor"
wait "$monitor" || true
published=$(python3 -c '
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
print(sum(1 for j in lines if "rule" in j or "incident" in j) + 1)  # and "offline" at the end
' bounded.jsonl)
[ "$published" -gt 10 ] || fail "the faults capture gave $published messages"
grep -q -- "--mqtt: the queue holds 5 messages: dropping the oldest" bounded.err ||
  fail "no word of the full queue: $(cat bounded.err)"
grep -q -- "--mqtt: $((published - 5)) messages dropped, the oldest first" bounded.err ||
  fail "$published messages published to a queue of 5: $(cat bounded.err)"
grep -q -- "--mqtt: 5 messages not acknowledged by the broker at the end" bounded.err ||
  fail "the 5 kept: $(cat bounded.err)"
echo "ok with no broker, a queue of 5 kept 5 of $published messages and said so"

# mqtts://: a broker that wants TLS and a client certificate from our CA.
kill "$broker"
wait "$broker" 2>/dev/null || true
openssl req -x509 -newkey rsa:2048 -nodes -days 2 -subj /CN=test-ca -keyout ca.key -out ca.pem 2>/dev/null
for who in server client; do
  openssl req -newkey rsa:2048 -nodes -subj "/CN=$who" -keyout "$who.key" -out "$who.csr" 2>/dev/null
  openssl x509 -req -in "$who.csr" -CA ca.pem -CAkey ca.key -CAcreateserial -days 2 -out "$who.pem" \
    -extfile <(printf 'subjectAltName=DNS:localhost,IP:127.0.0.1\n') 2>/dev/null
done
tls_port=$(free_port)
cat >tls.conf <<CONF
listener $tls_port 127.0.0.1
allow_anonymous true
user root
cafile $WORK/ca.pem
certfile $WORK/server.pem
keyfile $WORK/server.key
require_certificate true
CONF
mosquitto -c tls.conf >tls.log 2>&1 &
broker=$!
tls_sub() {
  mosquitto_sub -p "$tls_port" --cafile ca.pem --cert client.pem --key client.key -t "tls/status" -C 1 -W 3
}
wait_for 50 mosquitto_sub -p "$tls_port" --cafile ca.pem --cert client.pem --key client.key -t probe -W 1 -C 1 -E ||
  fail "the TLS broker did not start: $(tail -3 tls.log)"
"$NCSERVO" monitor -i "$host" --mqtt "mqtts://127.0.0.1:$tls_port/tls" --mqtt-ca ca.pem \
  --mqtt-cert client.pem --mqtt-key client.key >/dev/null 2>tls.err &
monitor=$!
wait_for 50 grep -q "connected to" tls.err || fail "mqtts: no connection: $(cat tls.err)"
[ "$(tls_sub)" = online ] || fail "mqtts: not online"
kill -INT "$monitor"
wait "$monitor" 2>/dev/null || true
[ "$(tls_sub)" = offline ] || fail "mqtts: not offline at the end"
"$NCSERVO" monitor -i "$host" --mqtt "mqtts://127.0.0.1:$tls_port/tls" --mqtt-ca ca.pem \
  --mqtt-flush 0 --duration 2 >/dev/null 2>notls.err || true
! grep -q "connected to" notls.err || fail "mqtts without a client certificate connected: $(cat notls.err)"
echo "ok mqtts with a client certificate connects, without one it does not"
echo PASS
