#!/usr/bin/env bash
# simulate_diagnosis.sh SRC BUILD
# `ncservo simulate --diagnosis` (docs/simulate.md#diagnosis) against its own truth: on a capture
# with drive faults, a bad cable, an SDO abort, a clock out of sync and a sync error, and on the incidents
# scenario in the TwinCAT style as a pcapng, `validate`'s JSON lists every emergency, SDO answer
# and abort, counter rise and link fault of --diagnosis-truth on its frame (and nothing else), and
# every incident of --incidents-truth with its cause (link-fault and sync-error among them). The
# truth is refused where the records are not the bus's frames. (The plugin against validate on
# the same kind of capture: plugin_drive_messages.sh.)
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

# compare NAME CAPTURE TRUTH KINDS: validate's report against the simulator's truth; KINDS the
# kinds of item the truth must hold.
compare() {
  local name=$1 capture=$2 truth=$3 kinds=$4
  "$NCSERVO" validate --format json --fail-on never "$capture" >"$WORK/$name.json" ||
    fail "$name: validate exited $?"
  python3 - "$name" "$WORK/$name.json" "$truth" "$kinds" <<'PY' || exit 1
import json, sys
name, report, truth_file, kinds = sys.argv[1:]
capture = json.load(open(report))["captures"][0]
truth = json.load(open(truth_file))

def said(m):
    item = (m["frame"], m["station"], m["kind"], m.get("request_frame"))
    if m["kind"] == "emergency":
        return item + (m["code"], m["register"])
    return item + (m["index"], m["subindex"], m.get("value"), m.get("abort"))

want = sorted(said(m) for m in truth["drive_messages"])
got = sorted(said(m) for m in capture["drive_messages"])
counters = lambda items: sorted((e["frame"], e["station"], e["port"], e["counter"], e["delta"]) for e in items)
# a link names the slave and port whose counters rose: the downstream end of a port-0 link
ends = lambda f: [f["downstream"]] + ([f["upstream"]] if f.get("upstream") else [])
links_got = sorted((f["frame"], e["station"], e["port"], f["errors"])
                   for f in capture["link_faults"] for e in ends(f)
                   if any(t["frame"] == f["frame"] and t["station"] == e["station"] and t["port"] == e["port"]
                          for t in truth["link_faults"]))
links_want = sorted((t["frame"], t["station"], t["port"], t["errors"]) for t in truth["link_faults"])
problems = []
if got != want:
    problems.append(f"drive messages: only in the truth {[m for m in want if m not in got][:4]}, "
                    f"only in validate {[m for m in got if m not in want][:4]}")
if counters(capture["esc_errors"]) != counters(truth["esc_errors"]):
    problems.append(f"counter rises: validate {counters(capture['esc_errors'])[:6]}, "
                    f"truth {counters(truth['esc_errors'])[:6]}")
if links_got != links_want or len(capture["link_faults"]) != len(truth["link_faults"]):
    problems.append(f"link faults: validate {capture['link_faults']}, truth {truth['link_faults']}")
if capture.get("mailbox_notes"):
    problems.append(f"mailbox notes: {capture['mailbox_notes'][:3]}")
have = {m["kind"] for m in truth["drive_messages"]} | ({"esc"} if truth["esc_errors"] else set()) \
    | ({"link"} if truth["link_faults"] else set())
missing = [k for k in kinds.split() if k not in have]
if missing:
    problems.append(f"the truth was to hold {missing} and holds {sorted(have)}")
for p in problems:
    print(f"{name}: {p}", file=sys.stderr)
if problems:
    sys.exit(1)
print(f"{name}: {len(want)} drive messages, {len(truth['esc_errors'])} counter rises, "
      f"{len(links_want)} link faults as the simulator said")
PY
}

"$NCSERVO" simulate --diagnosis --bad-link 0x3EB:0@1.2x3 --fault MBX-003@0.9:0 --fault DC-001@1.0:3 \
  --sync-error 0x3EA@1.6 \
  -o "$WORK/said.pcap" --diagnosis-truth "$WORK/said.truth.json" 2>"$WORK/err.txt" ||
  fail "simulate exited $?: $(cat "$WORK/err.txt")"
compare said "$WORK/said.pcap" "$WORK/said.truth.json" "emergency sdo-upload sdo-abort esc link"
python3 - "$WORK/said.json" <<'PY' || fail "said: the findings, the drive messages' axes or the link fault's cause differ"
import json, sys
capture = json.load(open(sys.argv[1]))["captures"][0]
fired = {f["rule"] for f in capture["findings"]}
# the bad link's 3 lost frames (COM-004; COM-003 on the axes before it, whose drives got them),
# the link it names, the abort, the clock out of sync and axis 1's slave leaving OP: nothing else
assert fired == {"COM-003", "COM-004", "LNK-001", "MBX-003", "DC-001", "ESM-003"}, sorted(fired)
assert all(m["axis"] is not None for m in capture["drive_messages"]), "a drive message without its axis"
causes = {(i["kind"], i["axis"], i["cause"]["id"]) for i in capture["incidents"]}
assert {("drive-fault", 2, "link-fault"), ("drive-fault", 3, "link-fault"),
        ("esm", 1, "sync-error")} <= causes, causes
sync = [f for f in capture["findings"] if f["rule"] == "ESM-003"]
assert len(sync) == 1 and "0x001A" in sync[0]["message"] and sync[0]["axis"] == 1, sync
PY

"$NCSERVO" simulate --scenario incidents --diagnosis --image twincat --cycle-us 2000 --duration 8 \
  --seed 11 -o "$WORK/day.pcapng" --diagnosis-truth "$WORK/day.truth.json" \
  --incidents-truth "$WORK/day.incidents.json" 2>"$WORK/err.txt" ||
  fail "simulate --scenario incidents exited $?: $(cat "$WORK/err.txt")"
compare day "$WORK/day.pcapng" "$WORK/day.truth.json" "emergency sdo-upload esc link"
python3 "$SRC/tests/tools/check_incidents.py" "$WORK/day.incidents.json" --report "$WORK/day.json" ||
  fail "day: validate's incidents differ from the truth"
python3 - "$WORK/day.json" <<'PY' || fail "day: the sync error or the link fault is not told as it happened"
import json, sys
capture = json.load(open(sys.argv[1]))["captures"][0]
by_cause = {i["cause"]["id"]: i for i in capture["incidents"]}
assert "0x001A" in by_cause["sync-error"]["cause"]["text"], by_cause["sync-error"]["cause"]
assert "port 0" in by_cause["link-fault"]["cause"]["text"], by_cause["link-fault"]["cause"]
PY

# The truth is the bus's frames: refused where the capture's records are not.
set +e
"$NCSERVO" simulate --diagnosis --capture-stamps bunched:4ms -o "$WORK/shaped.pcap" \
  --diagnosis-truth "$WORK/shaped.json" 2>"$WORK/err.txt"
rc=$?
set -e
[ $rc = 2 ] && grep -q "not the bus's frames" "$WORK/err.txt" ||
  fail "--diagnosis-truth with a capture shape: exit $rc, $(cat "$WORK/err.txt")"
echo "simulate_diagnosis: validate reports what the simulated drives and ESCs said, where they said it"
