#!/usr/bin/env bash
# eni_tasks.sh SRC BUILD
# An ENI with a second task (docs/layout.md#eni-cycle-times): `simulate --io-task-us` writes one
# <Cyclic> per task, each with its own <CycleTime>; `validate --eni` on the capture reads every
# <Cyclic> (the servos' frame in either), reports no COM-002 and no layout warning, and finds what
# inference finds. An ENI that gives the slower task's frame the servo task's cycle time gets one
# warning naming that frame.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"

"$NCSERVO" simulate --no-startup --io-slaves 4 --io-task-us 10000 --duration 3 \
  --fault SE-001@0.6:0 -o "$WORK/t.pcap" --eni "$WORK/t.xml" 2>/dev/null || fail "simulate"
# The ENI as written, the one-task form (every frame in one <Cyclic> at 1000 us), and the tasks
# in the other order.
python3 - "$WORK/t.xml" "$WORK/one-task.xml" "$WORK/swapped.xml" <<'PY' || fail "ENI: not one <Cyclic> per task"
import copy, sys, xml.etree.ElementTree as ET
tree = ET.parse(sys.argv[1])
config = tree.getroot().find("Config")
cyclics = config.findall("Cyclic")
times = [c.findtext("CycleTime") for c in cyclics]
assert times == ["1000", "10000"], times
assert all(len(c.findall("Frame")) == 1 for c in cyclics), [len(c.findall("Frame")) for c in cyclics]
one = copy.deepcopy(tree)
first, second = one.getroot().find("Config").findall("Cyclic")
for frame in second.findall("Frame"):
    first.append(frame)
one.getroot().find("Config").remove(second)
one.write(sys.argv[2])
for c in cyclics:
    config.remove(c)
config.extend(reversed(cyclics))
tree.write(sys.argv[3])
PY

"$NCSERVO" validate --format jsonl --fail-on never "$WORK/t.pcap" | grep '"rule"' >"$WORK/inferred.jsonl"
grep -q '"rule":"SE-001"' "$WORK/inferred.jsonl" || fail "inference: no SE-001"
for eni in t swapped; do
  "$NCSERVO" validate --format jsonl --fail-on never --eni "$WORK/$eni.xml" "$WORK/t.pcap" \
    >"$WORK/$eni.jsonl" 2>"$WORK/$eni.err" || fail "$eni: validate --eni exit $?"
  ! grep -q '"COM-002"' "$WORK/$eni.jsonl" || fail "$eni: COM-002: $(grep -m1 COM-002 "$WORK/$eni.jsonl")"
  ! grep -q '"warnings"' "$WORK/$eni.jsonl" || fail "$eni: $(grep -m1 warnings "$WORK/$eni.jsonl")"
  cmp -s <(grep '"rule"' "$WORK/$eni.jsonl") "$WORK/inferred.jsonl" ||
    fail "$eni: findings differ from inference's: $(diff <(grep '"rule"' "$WORK/$eni.jsonl") \
      "$WORK/inferred.jsonl" | head -3)"
  "$NCSERVO" validate --fail-on never --eni "$WORK/$eni.xml" "$WORK/t.pcap" | grep -q '^layout: eni, 4 axes' ||
    fail "$eni: the ENI's layout not used"
done

"$NCSERVO" validate --fail-on never --eni "$WORK/one-task.xml" "$WORK/t.pcap" >"$WORK/one.txt" 2>&1
[ "$(grep -c '^warning: layout does not fit: ' "$WORK/one.txt")" = 1 ] &&
  grep -q "^warning: layout does not fit: the ENI's cyclic frame of LRW 0x00011000 (4 bytes) has the cycle time 1000 us of its task; the capture shows it every 10000.0 us" "$WORK/one.txt" ||
  fail "one-task ENI: $(grep 'warning' "$WORK/one.txt")"
echo "eni_tasks: one <Cyclic> per task with its cycle time; validate --eni finds what inference finds, no COM-002"
