#!/usr/bin/env bash
# wall_clock.sh SRC BUILD: times of day and the report's scope (docs/cli.md#times-of-day, #scope,
# #time-window) and incidents in `annotate` (docs/field.md). The times are held to stock tshark's
# frame.time_epoch of the same frames, not to ncservo's own JSON.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_program tshark python3
CAPTURE="$SRC/captures/sim-incidents-4axis.pcap"

tshark -r "$CAPTURE" -T fields -e frame.number -e frame.time_epoch >"$WORK/epochs.tsv" \
  || fail "tshark could not read $CAPTURE"
"$NCSERVO" validate --fail-on never --format json "$CAPTURE" >"$WORK/all.json"
"$NCSERVO" validate --fail-on never "$CAPTURE" >"$WORK/utc.txt"
TZ=CET-1CEST,M3.5.0,M10.5.0/3 "$NCSERVO" validate --fail-on never --local-time "$CAPTURE" \
  >"$WORK/local.txt"

# The start line, each group's first frame and each incident's time of day, in UTC and in CET.
python3 - "$WORK/epochs.tsv" "$WORK/all.json" "$WORK/utc.txt" "$WORK/local.txt" <<'PY' || fail "times of day"
import datetime as dt, json, re, sys
epoch = {}
for line in open(sys.argv[1]):
    n, t = line.split()
    epoch[int(n)] = t
report = json.load(open(sys.argv[2]))["captures"][0]
def day_time(frame, tz):
    seconds, _, fraction = epoch[frame].partition(".")
    when = dt.datetime.fromtimestamp(int(seconds), tz)
    return when.strftime("%H:%M:%S") + "." + (fraction + "000")[:3]
utc = dt.timezone.utc
for path, tz, zone_word in ((sys.argv[3], utc, "UTC"), (sys.argv[4], None, "local time")):
    text = open(path).read()
    if tz is None:  # CET in winter, CEST in summer (the TZ rule the run was given)
        first = dt.datetime.fromtimestamp(int(epoch[1].split(".")[0]), utc)
        summer = dt.datetime(first.year, 3, 31, tzinfo=utc) <= first < dt.datetime(first.year, 10, 27, tzinfo=utc)
        tz = dt.timezone(dt.timedelta(hours=2 if summer else 1))
    seconds, _, fraction = epoch[1].partition(".")
    when = dt.datetime.fromtimestamp(int(seconds), tz)
    offset = when.strftime("%z")
    zone = "Z" if tz is utc else offset[:3] + ":" + offset[3:]
    start = when.strftime("%Y-%m-%dT%H:%M:%S") + "." + (fraction + "000000")[:6] + zone
    want = f"start: {start} (times of day in {zone_word})"
    assert want in text, f"{path}: no '{want}' in\n" + text[:600]
    groups = re.findall(r"frames? (\d+) \(\d+\.\d+ s, (\d\d:\d\d:\d\d\.\d{3})\)", text)
    assert groups, f"{path}: no finding group with a time of day"
    for frame, shown in groups:
        assert shown == day_time(int(frame), tz), (path, frame, shown, day_time(int(frame), tz))
    incidents = re.findall(r"at frame (\d+), \d+\.\d{3} s \((\d\d:\d\d:\d\d\.\d{3})\)", text)
    assert len(incidents) == len(report["incidents"]) > 0, (len(incidents), len(report["incidents"]))
    for frame, shown in incidents:
        assert shown == day_time(int(frame), tz), (path, frame, shown)
PY

# --from/--to as ISO times give what the same window in seconds gives.
read -r from_iso to_iso from_cet < <(python3 - "$WORK/epochs.tsv" <<'PY'
import datetime as dt, sys
first = float(open(sys.argv[1]).readline().split()[1])
at = lambda s, tz: dt.datetime.fromtimestamp(first + s, tz).isoformat(timespec="microseconds")
utc = dt.timezone.utc
print(at(1.0, utc).replace("+00:00", "Z"), at(2.0, utc).replace("+00:00", "Z"),
      at(1.0, dt.timezone(dt.timedelta(hours=1))))
PY
)
"$NCSERVO" validate --fail-on never --format json --from 1 --to 2 "$CAPTURE" >"$WORK/seconds.json"
"$NCSERVO" validate --fail-on never --format json --from "$from_iso" --to "$to_iso" "$CAPTURE" \
  >"$WORK/iso.json" || fail "--from $from_iso --to $to_iso: exit $?"
"$NCSERVO" validate --fail-on never --format json --from "$from_cet" --to 2 "$CAPTURE" \
  >"$WORK/mixed.json" || fail "--from $from_cet --to 2: exit $?"
python3 - "$WORK/seconds.json" "$WORK/iso.json" "$WORK/mixed.json" <<'PY' || fail "ISO windows"
import json, sys
def seen(path):
    c = json.load(open(path))["captures"][0]
    return [(f["rule"], f["frame"]) for f in c["findings"]], [i["frame"] for i in c["incidents"]], c["frames"]
want = seen(sys.argv[1])
assert want[0] or want[1], "the window holds nothing to compare"
for path in sys.argv[2:]:
    assert seen(path) == want, (path, seen(path)[:2], want[:2])
PY
rc=0
"$NCSERVO" validate --from "2026-13-01T00:00:00Z" "$CAPTURE" >/dev/null 2>"$WORK/bad.err" || rc=$?
[ "$rc" = 2 ] || fail "a month 13: exit $rc, expected 2"
grep -q 'ISO 8601' "$WORK/bad.err" || fail "a month 13: $(cat "$WORK/bad.err")"

# --axis and --only: exactly the named axis's and the bus's findings and incidents.
axis=$(python3 -c 'import json,sys; c=json.load(open(sys.argv[1]))["captures"][0]; print(c["incidents"][0]["axis_name"])' "$WORK/all.json")
"$NCSERVO" validate --fail-on never --format json --axis "$axis" "$CAPTURE" >"$WORK/axis.json"
"$NCSERVO" validate --fail-on never --format json --only incidents "$CAPTURE" >"$WORK/incidents.json"
"$NCSERVO" validate --fail-on never --format json --only findings "$CAPTURE" >"$WORK/findings.json"
python3 - "$WORK/all.json" "$WORK/axis.json" "$WORK/incidents.json" "$WORK/findings.json" "$axis" <<'PY' || fail "--axis/--only"
import json, sys
load = lambda p: json.load(open(p))["captures"][0]
whole, axis, incidents, findings = map(load, sys.argv[1:5])
name = sys.argv[5]
keep = lambda items: [(i.get("rule"), i["frame"]) for i in items if i.get("axis_name") in (name, None)]
every = lambda items: [(i.get("rule"), i["frame"]) for i in items]
assert every(axis["findings"]) == keep(whole["findings"]), "findings of --axis"
assert every(axis["incidents"]) == keep(whole["incidents"]), "incidents of --axis"
assert len(every(axis["findings"])) < len(every(whole["findings"])), "--axis left nothing out"
assert axis["scope"] == f"axis {name} and the bus", axis["scope"]
assert incidents["findings"] == [] and every(incidents["incidents"]) == every(whole["incidents"])
assert sum(incidents["summary"].values()) == 0, incidents["summary"]
assert findings["incidents"] == [] and every(findings["findings"]) == every(whole["findings"])
PY
rc=0
"$NCSERVO" validate --axis nosuchaxis "$CAPTURE" >/dev/null 2>"$WORK/axis.err" || rc=$?
[ "$rc" = 2 ] || fail "--axis nosuchaxis: exit $rc, expected 2"
grep -q "no axis of that name (its axes: .*$axis" "$WORK/axis.err" || fail "--axis nosuchaxis: $(cat "$WORK/axis.err")"

# annotate: one INC- comment per incident, on its frame, and still one after annotating again.
"$NCSERVO" annotate "$CAPTURE" "$WORK/once.pcapng" 2>/dev/null
"$NCSERVO" annotate "$WORK/once.pcapng" "$WORK/twice.pcapng" 2>/dev/null
for copy in once twice; do
  tshark -r "$WORK/$copy.pcapng" -Y frame.comment -T fields -E occurrence=a -E aggregator='|' \
    -e frame.number -e frame.comment >"$WORK/$copy.tsv"
  python3 - "$WORK/all.json" "$WORK/$copy.tsv" <<'PY' || fail "annotate $copy: incidents"
import json, sys
report = json.load(open(sys.argv[1]))["captures"][0]
want = sorted((i["frame"], "INC-" + i["cause"]["id"]) for i in report["incidents"])
have = []
for line in open(sys.argv[2]):
    frame, comments = line.rstrip("\n").split("\t", 1)
    for comment in comments.split("|"):
        if comment.startswith("INC-"):
            have.append((int(frame), comment.split(" ", 1)[0]))
            assert "evidence: " in comment or "recovery: " in comment, comment
assert sorted(have) == want, (sorted(have), want)
PY
done
echo "wall_clock: times of day match tshark's, ISO windows equal second windows, --axis/--only keep their part, annotate writes each incident once"
