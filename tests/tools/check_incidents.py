#!/usr/bin/env python3
"""Compare the incidents a tool found with the truth of the capture's maker.

    check_incidents.py TRUTH.json --report REPORT.json   # `ncservo validate --format json`
    check_incidents.py TRUTH.json --tshark FIELDS.tsv    # tshark -Y ncservo.incident -T fields
                                                         #   -e frame.number -e ncservo.axis
                                                         #   -e ncservo.incident

TRUTH is what `ncservo simulate --incidents-truth` and `gen_capture.py --incidents` write:
{"incidents": [{"kind": ..., "axis": N or null, "frame": F, "cause": "id"}, ...]}.

With --report every truth incident must be in the first capture's `incidents` with the same
kind, axis, frame and cause id (`cause.id`), and nothing more.  With --tshark each frame must
carry exactly the truth's incidents of that frame, by cause id (the first cause id in each
ncservo.incident value; tshark's -E aggregator=| keeps the values apart); the axes are compared too when the frame lists one ncservo.axis per
incident.  Exit 0 when they agree, 1 with every difference listed, 2 when an input cannot be read
(a report without `incidents` is that: the detector is missing).
"""

import argparse
import collections
import json
import re
import sys

# INTERFACES.md "Incidents": the cause ids, longest first so that an alternation takes the whole id.
CAUSE_IDS = ("link-fault", "communication-loss", "sync-error", "overtemperature", "following-error-after-step",
             "following-error", "overcurrent", "bus-voltage", "encoder", "overspeed",
             "configuration", "nc-command", "unknown")
CAUSE_ID = re.compile("|".join(sorted(CAUSE_IDS, key=len, reverse=True)))
AGGREGATOR = "|"  # tshark -E aggregator: the incident texts may hold commas


def load_truth(path):
    with open(path, encoding="utf-8") as f:
        incidents = json.load(f)["incidents"]
    return [(i["kind"], i["axis"], int(i["frame"]), i["cause"]) for i in incidents]


def describe(incident):
    kind, axis, frame, cause = incident
    where = "the bus" if axis is None else f"axis {axis}"
    return f"{kind} on {where} at frame {frame}, cause {cause}"


def found_in_report(path):
    with open(path, encoding="utf-8") as f:
        report = json.load(f)
    capture = report["captures"][0]
    if "incidents" not in capture:
        raise ValueError(f"{path} has no `incidents` (no incident detector in this build: "
                         "INTERFACES.md \"Incidents\")")
    found = []
    for i in capture["incidents"]:
        cause = i.get("cause")
        cause_id = cause.get("id") if isinstance(cause, dict) else cause
        found.append((i.get("kind"), i.get("axis"), i.get("frame"), cause_id))
    return found


def compare(truth, found):
    """Differences between two lists of incidents, as a multiset."""
    want, got = collections.Counter(truth), collections.Counter(found)
    missing = sorted((want - got).elements(), key=lambda i: i[2])
    extra = sorted((got - want).elements(), key=lambda i: (i[2] or 0))
    return ([f"missing: {describe(i)}" for i in missing]
            + [f"not in the truth: {describe(i)}" for i in extra])


def compare_tshark(truth, path):
    """Per frame: the cause ids of the truth's incidents and of ncservo.incident."""
    want = collections.defaultdict(list)
    for kind, axis, frame, cause in truth:
        want[frame].append((cause, axis))
    got = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            columns = line.rstrip("\n").split("\t")
            if not columns or not columns[0].strip():
                continue
            frame = int(columns[0])
            axes = [a for a in (columns[1] if len(columns) > 1 else "").split(AGGREGATOR) if a]
            values = [v for v in (columns[2] if len(columns) > 2 else "").split(AGGREGATOR) if v]
            causes = []
            for value in values:
                match = CAUSE_ID.search(value)
                causes.append(match.group(0) if match else value)
            got[frame] = (causes, axes)
    problems = []
    for frame in sorted(set(want) | set(got)):
        expected = want.get(frame, [])
        causes, axes = got.get(frame, ([], []))
        if sorted(c for c, _ in expected) != sorted(causes):
            problems.append(f"frame {frame}: ncservo.incident {sorted(causes) or 'none'}, the "
                            f"truth {sorted(c for c, _ in expected) or 'none'}")
            continue
        if expected and len(axes) == len(causes):
            truth_axes = sorted("" if a is None else str(a) for _, a in expected)
            shown = sorted("" if a in ("", "-1") else a for a in axes)
            if any(a is not None for _, a in expected) and truth_axes != shown:
                problems.append(f"frame {frame}: ncservo.axis {shown}, the truth {truth_axes}")
    return problems


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("truth")
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--report", help="ncservo validate --format json output")
    source.add_argument("--tshark", help="tshark fields: frame.number, ncservo.axis, "
                                         "ncservo.incident (tab-separated)")
    args = p.parse_args(argv)
    try:
        truth = load_truth(args.truth)
        if args.report:
            problems = compare(truth, found_in_report(args.report))
        else:
            problems = compare_tshark(truth, args.tshark)
    except (OSError, ValueError, KeyError, IndexError, TypeError) as e:
        print(f"check_incidents: {e}", file=sys.stderr)
        return 2
    for problem in problems:
        print(f"check_incidents: {problem}", file=sys.stderr)
    if problems:
        print(f"check_incidents: {len(problems)} differences from {len(truth)} incidents in "
              f"{args.truth}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
