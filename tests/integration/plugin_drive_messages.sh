#!/usr/bin/env bash
# plugin_drive_messages.sh SRC BUILD
# What the drives and the ESCs said (docs/drive-messages.md) is the same in `tshark -2` with the
# plugin as in `validate`'s report, frame by frame and slave by slave: every emergency (code,
# register, data), SDO answer and abort (index, subindex, value, abort code, request frame), ESC
# counter rise (station, port, counter, rise) and link fault (its text), each in the ncservo layer
# of its slave. Checked on the independent generator's captures with the §11 injections and the
# link-fault incident and on the simulator's with --diagnosis (which must hold each kind), and on
# every real capture, where the plugin's
# SDO index, subindex and expedited value must also be what stock tshark's ecat_mailbox.coe.*
# fields show on the same frame.
SRC=$1 BUILD=$2
source "$SRC/tests/integration/lib.sh"
require_program tshark
chmod a+rx "$WORK"

fields=(-e frame.number -e ecat_mailbox.coe.sdoidx -e ecat_mailbox.coe.sdosub -e ecat_mailbox.coe.sdodata)

# compare NAME CAPTURE KINDS: KINDS the kinds the capture must hold ("" for none required).
compare() {
  local name=$1 capture=$2 kinds=$3
  chmod a+r "$capture"
  "$NCSERVO" validate --format json --fail-on never --allow-empty "$capture" >"$WORK/report.json" ||
    fail "$name: validate exited $?"
  "$TSHARK" "$PLUGIN" -2 -r "$capture" -Y 'ncservo.sdo.index || ncservo.emcy.code || ncservo.esc.delta || ncservo.link_fault' \
    -T pdml >"$WORK/plugin.pdml" 2>"$WORK/err.txt" || fail "$name: tshark exited $?: $(head -3 "$WORK/err.txt")"
  "$TSHARK" none -r "$capture" -Y ecat_mailbox.coe.sdoidx -T fields -E separator=' ' -E occurrence=a \
    "${fields[@]}" >"$WORK/stock.txt" 2>/dev/null || fail "$name: stock tshark exited $?"
  python3 - "$name" "$WORK/report.json" "$WORK/plugin.pdml" "$WORK/stock.txt" "$kinds" <<'PY' || exit 1
import json, sys
import xml.etree.ElementTree as ET
name, report, pdml, stock_file, kinds = sys.argv[1:]
capture = json.load(open(report))["captures"][0]

def slave_of(j):
    if j.get("station") is not None:
        return ("station", j["station"])
    # a broadcast read's sum of every slave's counters names no slave
    return ("position", j["position"]) if j.get("position") is not None else ("all", None)

cli = []
for m in capture["drive_messages"]:
    where = (m["frame"], slave_of(m))
    if m["kind"] == "emergency":
        cli.append(where + ("emergency", m["code"], m["register"], m["data"]))
    elif m["kind"] == "sdo-abort":
        cli.append(where + ("abort", m["index"], m["subindex"], m["abort"], m.get("request_frame")))
    else:
        cli.append(where + ("sdo", m["index"], m["subindex"], m["value"], m.get("request_frame")))
for e in capture["esc_errors"]:
    cli.append((e["frame"], slave_of(e), "esc", e["port"], e["counter"], e["delta"]))
for f in capture["link_faults"]:
    reported = f["downstream"] if f.get("upstream") is None or f["downstream"]["port"] == 0 else f["upstream"]
    cli.append((f["frame"], None, "link", f["text"]))

plugin = []
sdo_values = {}  # frame -> {(index, subindex): value}
for packet in ET.parse(pdml).getroot().iter("packet"):
    frame = None
    for proto in packet.findall("proto"):
        if proto.get("name") == "frame":
            for f in proto.iter("field"):
                if f.get("name") == "frame.number":
                    frame = int(f.get("show"))
        if proto.get("name") != "ncservo":
            continue
        label = proto.get("showname") or ""
        words = label.split()
        slave = (words[1], int(words[2], 16)) if len(words) >= 3 and words[1] in ("station", "position") \
            else ("all", None) if len(words) >= 2 and words[1] == "all" else None
        records = []
        for f in proto.iter("field"):
            key = f.get("name")
            show = f.get("show")
            starts = key in ("ncservo.emcy.code", "ncservo.sdo.index", "ncservo.esc.station", "ncservo.link_fault") or (
                key == "ncservo.esc.port" and (not records or "ncservo.esc.port" in records[-1]))
            if starts:
                records.append({})
            if records and key.startswith(("ncservo.emcy", "ncservo.sdo", "ncservo.esc", "ncservo.link_fault")):
                # bytes show as 00:0d:..., the JSON's data as 000d...
                records[-1].setdefault(key, show.replace(":", "") if key == "ncservo.emcy.data" else show)
        for r in records:
            num = lambda k: int(r[k], 0) if k in r else None
            if "ncservo.emcy.code" in r:
                plugin.append((frame, slave, "emergency", num("ncservo.emcy.code"),
                               num("ncservo.emcy.register"), r.get("ncservo.emcy.data")))
            elif "ncservo.sdo.abort" in r:
                plugin.append((frame, slave, "abort", num("ncservo.sdo.index"), num("ncservo.sdo.subindex"),
                               num("ncservo.sdo.abort"), num("ncservo.sdo.request_in")))
            elif "ncservo.sdo.index" in r:
                value = num("ncservo.sdo.value")
                plugin.append((frame, slave, "sdo", num("ncservo.sdo.index"), num("ncservo.sdo.subindex"),
                               value, num("ncservo.sdo.request_in")))
                sdo_values.setdefault(frame, {})[(num("ncservo.sdo.index"), num("ncservo.sdo.subindex"))] = value
            elif "ncservo.link_fault" in r:
                plugin.append((frame, None, "link", r["ncservo.link_fault"]))
            else:
                plugin.append((frame, slave, "esc", num("ncservo.esc.port"), r.get("ncservo.esc.counter"),
                               num("ncservo.esc.delta")))

# The fields the plugin showed, for the check that every one of them shows somewhere.
with open(pdml + ".shown", "a") as shown:
    for field in ET.parse(pdml).getroot().iter("field"):
        if (field.get("name") or "").startswith(("ncservo.emcy", "ncservo.sdo", "ncservo.errhist",
                                                 "ncservo.esc", "ncservo.link_fault")):
            shown.write(field.get("name") + "\n")

key = lambda t: tuple(str(x) for x in t)
if sorted(cli, key=key) != sorted(plugin, key=key):
    only_cli = [t for t in cli if t not in plugin][:5]
    only_plugin = [t for t in plugin if t not in cli][:5]
    print(f"{name}: validate and the plugin differ ({len(cli)} against {len(plugin)} items)\n"
          f"  only in validate: {only_cli}\n  only in the plugin: {only_plugin}")
    sys.exit(1)
have = {t[2] for t in cli}
missing = [k for k in kinds.split() if k not in have]
if missing:
    print(f"{name}: the capture was to hold {missing} and holds only {sorted(have)}")
    sys.exit(1)

# Stock tshark: the SDO index and subindex of every answer the plugin shows, and its expedited
# value where stock shows one (stock's Data is 32 bits).
checked = 0
stock = {}
for line in open(stock_file):
    parts = line.split()
    if len(parts) >= 3:
        stock[int(parts[0])] = parts[1:]
bad = []
for frame, objects in sdo_values.items():
    if frame not in stock:
        continue  # a download response without data, which stock does not decode (real_mailbox.sh)
    idx = [int(x, 16) for x in stock[frame][0].split(",")]
    sub = [int(x, 0) for x in stock[frame][1].split(",")]
    data = [int(x, 0) for x in stock[frame][2].split(",")] if len(stock[frame]) > 2 else []
    for (index, subindex), value in objects.items():
        if (index, subindex) not in zip(idx, sub):
            bad.append(f"frame {frame}: plugin 0x{index:04X}:{subindex}, stock {list(zip(idx, sub))}")
        elif value is not None and value < 1 << 32 and len(data) == 1 and data[0] != value:
            bad.append(f"frame {frame}: plugin value 0x{value:X}, stock 0x{data[0]:X}")
        checked += 1
if bad:
    print(f"{name}: the plugin and stock tshark differ:\n  " + "\n  ".join(bad[:5]))
    sys.exit(1)
print(f"{name}: {len(cli)} items the same in validate and tshark -2; {checked} SDO answers as stock decodes them")
PY
}

gen=$SRC/tests/tools/gen_capture.py
python3 "$gen" --axes 4 --cycles 3000 --seed 5 --inject MBX-003 --inject ERH-001 --inject LNK-002 \
  --incident link-fault -o "$WORK/gen-mailbox.pcap" >/dev/null || fail "gen_capture.py exited $?"
compare "gen-mailbox" "$WORK/gen-mailbox.pcap" "sdo abort esc link"
python3 "$gen" --axes 6 --cycles 3000 --seed 9 --format pcapng --inject LNK-001:1 --inject MBX-003:4 \
  -o "$WORK/gen-link.pcapng" >/dev/null || fail "gen_capture.py exited $?"
compare "gen-link" "$WORK/gen-link.pcapng" "esc link abort"
# A drive that reports its faults with emergencies, and the NC reading its newest 1003h entry: the
# rules that judge them name the axis by its station, which the layout file gives.
python3 "$gen" --axes 3 --cycles 3000 --seed 7 --inject MBX-002 --inject ERH-002 \
  --layout-config "$WORK/gen-drive.toml" -o "$WORK/gen-drive.pcap" >/dev/null || fail "gen_capture.py exited $?"
compare "gen-drive" "$WORK/gen-drive.pcap" "emergency sdo"
# The simulator's drives, which report each fault and answer the NC's reads of 1003h, an abort, a
# bad cable and the counters that name it.
"$NCSERVO" simulate --diagnosis --bad-link 0x3EB:0@1.2x3 --fault MBX-003@0.9:0 -o "$WORK/sim-said.pcap" \
  2>"$WORK/err.txt" || fail "simulate exited $?: $(cat "$WORK/err.txt")"
compare "sim-said" "$WORK/sim-said.pcap" "emergency sdo abort esc link"
# ... and its day at the machine in the TwinCAT style, a pcapng: the drives' words at each fault,
# a bad cable, a sync error's AL status polls.
"$NCSERVO" simulate --scenario incidents --diagnosis --image twincat --cycle-us 2000 --duration 8 \
  --seed 11 -o "$WORK/sim-day.pcapng" 2>"$WORK/err.txt" || fail "simulate exited $?: $(cat "$WORK/err.txt")"
compare "sim-day" "$WORK/sim-day.pcapng" "emergency sdo esc link"
# Every field of what was said (`ncservo fields`) showed on one of the generated captures.
"$NCSERVO" fields | awk -F'\t' '$3 !~ /^\(expert/ {print $1}' |
  grep -E '^ncservo\.(emcy|sdo|errhist|esc)\.|^ncservo\.link_fault$' | sort >"$WORK/wanted.txt"
sort -u "$WORK/plugin.pdml.shown" >"$WORK/shown.txt"
missing=$(comm -23 "$WORK/wanted.txt" "$WORK/shown.txt" | tr '\n' ' ')
[ -z "$missing" ] || fail "fields never shown on the generated captures: $missing"
require_path "$REAL_CAPTURES" "real captures" "the generated captures passed"
for capture in "$REAL_CAPTURES"/*.pcap "$REAL_CAPTURES"/*.pcapng "$REAL_CAPTURES"/*.cap; do
  [ -f "$capture" ] || continue
  # a copy the runner's user (nobody, under root) can read
  cp "$capture" "$WORK/real" && compare "$(basename "$capture")" "$WORK/real" ""
done
echo "plugin_drive_messages: the plugin shows what validate reports the drives and ESCs said"
