#!/usr/bin/env python3
"""check_vcd.py WAVES.vcd DECODE.jsonl FINDINGS.jsonl [MORE.vcd...]

Checks `ncservo decode --format vcd` (and each further VCD of the same capture, such as one read
back from FST) against `decode --format jsonl` and `validate --format
jsonl` of the same capture:
- every jsonl row: at its time, each field of its axis and its drive state in the VCD equal it;
- every value change of a field in the VCD equals the first jsonl row of that axis at or after
  its time (a master copy's outputs are written at their own time, the row at its returned copy's);
- the findings signals carry exactly the findings of validate, each at its frame's time.
Times go as the VCD writes them: nanoseconds since the first frame, never back.
"""
import bisect
import json
import struct
import sys
from collections import defaultdict

BUS = "bus"


def parse_vcd(path):
    """Returns (vars by id: (scope path, name, kind, width), changes by id: [(time, value)])."""
    variables, changes = {}, defaultdict(list)
    scopes, time, in_header = [], 0, True
    with open(path, encoding="utf-8") as f:
        tokens_pending = []
        for line in f:
            line = line.rstrip("\n")
            if in_header:
                tokens_pending += line.split()
                while "$end" in tokens_pending:
                    end = tokens_pending.index("$end")
                    command, tokens_pending = tokens_pending[:end], tokens_pending[end + 1:]
                    if not command:
                        continue
                    if command[0] == "$scope":
                        scopes.append(command[2])
                    elif command[0] == "$upscope":
                        scopes.pop()
                    elif command[0] == "$var":
                        kind, width, ident, name = command[1], int(command[2]), command[3], command[4]
                        assert ident not in variables, f"identifier {ident!r} declared twice"
                        variables[ident] = (tuple(scopes), name, kind, width)
                    elif command[0] == "$enddefinitions":
                        in_header = False
                        assert not scopes, "scopes left open"
                continue
            if not line or line in ("$dumpvars", "$end") or line.startswith("$comment"):
                continue
            if line[0] == "#":
                new_time = int(line[1:])
                assert new_time >= time, f"time goes back: #{new_time} after #{time}"
                time = new_time
            elif line[0] in "bBrRs":
                value, ident = line[1:].split(" ")
                changes[ident].append((time, line[0].lower() + value))
            else:
                changes[line[1:]].append((time, line[0]))
    return variables, changes


def vcd_value(kind, width, text):
    """The jsonl value a VCD value stands for (None: unknown)."""
    tag, body = text[0], text[1:]
    if tag == "s":
        return None if body == "\\000" else body
    if tag == "r":
        return struct.unpack("f", struct.pack("f", float(body)))[0]
    bits = body if tag == "b" else tag
    if "x" in bits:
        return None
    value = int(bits, 2)
    if kind == "integer" and len(bits) == width and bits[0] == "1":
        value -= 1 << width
    return value


def jsonl_value(value):
    if isinstance(value, float):
        return struct.unpack("f", struct.pack("f", value))[0]
    if isinstance(value, str):
        return value.replace(" ", "_")
    return value


def ns(seconds):
    return round(seconds * 1e9)


def main():
    decode_path, findings_path = sys.argv[2:4]
    vcd_paths = [sys.argv[1]] + sys.argv[4:]
    with open(decode_path, encoding="utf-8") as f:
        rows = [json.loads(line) for line in f]
    with open(findings_path, encoding="utf-8") as f:
        findings = [json.loads(line) for line in f]
        findings = [x for x in findings if "rule" in x]

    # Times as written: since the first frame, never back (in frame order).
    latest = 0
    events = sorted([(r["frame"], 0, i) for i, r in enumerate(rows)] +
                    [(x["frame"], 1, i) for i, x in enumerate(findings)])
    times = {}
    for frame, kind, i in events:
        latest = max(latest, ns((rows if kind == 0 else findings)[i]["time"]))
        times[(kind, i)] = latest

    scope_of = {}
    for r in rows:
        scope_of.setdefault(r["axis"], r["name"])
    # The last row of each axis at each time is what the VCD shows then.
    last_rows = {}
    for i, r in enumerate(rows):
        last_rows[(r["axis"], times[(0, i)])] = r
    ordered_rows = sorted(last_rows.items(), key=lambda kv: kv[0][1])
    # Findings: the same (scope, time, rule) in both, with as many of each.
    expected = defaultdict(int)
    for i, x in enumerate(findings):
        scope = BUS if x["axis"] is None else scope_of.get(x["axis"], f"axis{x['axis']}")
        expected[(scope, times[(1, i)], x["rule"])] += 1
    status = 0
    for vcd_path in vcd_paths:
        status |= check(vcd_path, ordered_rows, scope_of, expected)
    return status


def check(vcd_path, ordered_rows, scope_of, expected):
    """Checks one VCD against the rows in time order and the findings expected; 1 if it differs."""
    variables, changes = parse_vcd(vcd_path)
    # Per axis scope: field key ("scw.se", "ssp", "state") -> identifier.
    signals = defaultdict(dict)
    for ident, (scope, name, kind, width) in variables.items():
        axis = scope[0]
        field = name if len(scope) == 1 or scope[-1] == name else f"{scope[-1]}.{name}"
        signals[axis][field] = ident

    # Each signal's change times and the jsonl values they stand for, decoded once.
    decoded = {}
    for ident, history in changes.items():
        kind, width = variables[ident][2], variables[ident][3]
        decoded[ident] = ([t for t, _ in history], [vcd_value(kind, width, v) for _, v in history])

    errors = []
    checked = 0
    rows_by_axis = defaultdict(list)
    # Rows in time order, each signal's changes walked alongside: a signal whose VCD value and
    # jsonl value are both as at the row before still agree, so only a change is compared.
    cursor = {}  # identifier -> [index of its last change at or before the row, the row's value]
    unset = object()
    for (axis, time), r in ordered_rows:
        rows_by_axis[axis].append((time, r))
        scope = scope_of[axis]
        if scope not in signals:
            errors.append(f"axis {axis} ({scope}) has no scope in the VCD")
            continue
        for key, value in r.items():
            if key in ("frame", "time", "axis", "name", "message"):
                continue
            ident = signals[scope].get(key)
            if ident is None:
                errors.append(f"field {key} has no signal in {scope}")
                continue
            change_times, values = decoded.get(ident, ((), ()))
            at = cursor.setdefault(ident, [-1, unset])
            k = at[0]
            while k + 1 < len(change_times) and change_times[k + 1] <= time:
                k += 1
            checked += 1
            if k != at[0] or value != at[1]:
                got = values[k] if k >= 0 else None
                if got != jsonl_value(value):
                    errors.append(f"{scope}.{key} at {time} ns (frame {r['frame']}): "
                                  f"VCD {got!r}, jsonl {value!r}")
            at[0], at[1] = k, value

    # Each change of a field equals the first row at or after it.
    for axis, axis_rows in rows_by_axis.items():
        scope = scope_of[axis]
        row_times = [t for t, _ in axis_rows]
        for field, ident in signals[scope].items():
            if field in ("state", "findings"):
                continue
            for time, value in zip(*decoded.get(ident, ((), ()))):
                if value is None:
                    continue
                k = bisect.bisect_left(row_times, time)
                if k == len(row_times):
                    errors.append(f"{scope}.{field} changes at {time} ns after the last row")
                    continue
                row = axis_rows[k][1]
                if field in row and jsonl_value(row[field]) != value:
                    errors.append(f"{scope}.{field} changes to {value!r} at {time} ns; the next "
                                  f"row (frame {row['frame']}) has {row[field]!r}")
                checked += 1

    shown = defaultdict(int)
    for ident, (scope, name, kind, width) in variables.items():
        if name != "findings":
            continue
        # Several findings at one time are written one by one, each change adding one.
        previous, previous_time = [], None
        for time, text in changes.get(ident, []):
            value = vcd_value(kind, width, text)
            rules = value.split(",") if value else []
            before = previous if previous_time == time else []
            for rule in rules[len(before):]:
                shown[(scope[0], time, rule)] += 1
            previous, previous_time = rules, time
    if shown != expected:
        missing = {k: v for k, v in expected.items() if shown.get(k) != v}
        extra = {k: v for k, v in shown.items() if expected.get(k) != v}
        errors.append(f"findings differ: validate only {sorted(missing.items())[:5]}, "
                      f"VCD only {sorted(extra.items())[:5]}")

    if errors:
        for e in errors[:20]:
            print(f"FAIL: {vcd_path}: {e}", file=sys.stderr)
        print(f"{vcd_path}: {len(errors)} differences", file=sys.stderr)
        return 1
    print(f"{vcd_path}: {checked} values and {sum(expected.values())} findings agree")
    return 0


if __name__ == "__main__":
    sys.exit(main())
