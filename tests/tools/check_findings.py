#!/usr/bin/env python3
"""Compare the findings of `ncservo validate --format json` with those gen_capture.py expects.

    check_findings.py [--capture N|PATH] [--verbose] REPORT.json EXPECTED.json

REPORT is the validator's JSON document ({"captures": [{"findings": [{"rule", "axis", "frame",
"severity", ...}]}]}, docs/cli.md), or its jsonl output (one finding per line).  EXPECTED is
written by `gen_capture.py --findings`: {"expected": [{"rule", "axis", "first_frame",
"last_frame"}], "companions": {"RULE": ["RULE", ...]}}.

The check passes when
  - every expected finding is matched by its own reported finding with the same rule, the same
    axis (null for a bus finding) and a frame inside [first_frame, last_frame] (for a timed
    rule the window starts a cycle before its due_frame, not where its condition began: a
    finding reported before its timeout does not match), and
  - every other reported finding, of any severity, is a companion of an injected rule
    (companions may be reported any number of times, or not at all).

Exit status: 0 pass, 1 a finding is missing or unexpected, 2 an input could not be read.
"""

import argparse
import collections
import json
import sys

class InputError(Exception):
    pass


def load_json(path):
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        raise InputError(f"{path}: {e.strerror}") from None
    if not text.strip():  # a validator that died before writing must not pass as "no findings"
        raise InputError(f"{path}: empty")
    try:
        return json.loads(text)
    except json.JSONDecodeError as first_error:
        lines = [line for line in text.splitlines() if line.strip()]
        try:  # jsonl: one finding per line
            return [json.loads(line) for line in lines]
        except json.JSONDecodeError:
            raise InputError(f"{path}: not JSON: {first_error}") from None


def pick_capture(document, path, which):
    """The findings list of one capture of the report."""
    if isinstance(document, list):  # jsonl
        return document
    if not isinstance(document, dict) or not isinstance(document.get("captures"), list):
        raise InputError(f"{path}: expected an object with a \"captures\" list")
    captures = document["captures"]
    if which is None:
        if len(captures) != 1:
            raise InputError(f"{path}: {len(captures)} captures; choose one with --capture")
        capture = captures[0]
    elif which.isdigit() and int(which) < len(captures):
        capture = captures[int(which)]
    else:
        matches = [c for c in captures if isinstance(c, dict) and c.get("path") == which]
        if len(matches) != 1:
            raise InputError(f"{path}: no capture {which!r}")
        capture = matches[0]
    if not isinstance(capture, dict) or not isinstance(capture.get("findings"), list):
        raise InputError(f"{path}: the capture has no \"findings\" list")
    return capture["findings"]


def is_axis(value):
    return value is None or (isinstance(value, int) and not isinstance(value, bool))


def is_frame(value):
    return isinstance(value, int) and not isinstance(value, bool) and value >= 1


def read_reported(findings, path):
    reported = []
    for i, f in enumerate(findings):
        where = f"{path}: finding {i + 1}"
        if not isinstance(f, dict):
            raise InputError(f"{where}: not an object")
        rule, axis, frame = f.get("rule"), f.get("axis"), f.get("frame")
        if not isinstance(rule, str) or not is_axis(axis) or not is_frame(frame):
            raise InputError(f"{where}: needs \"rule\" (string), \"axis\" (integer or null) and "
                             f"\"frame\" (integer >= 1): {json.dumps(f)[:200]}")
        severity = f.get("severity", "error")
        reported.append({"rule": rule, "axis": axis, "frame": frame,
                         "severity": severity if isinstance(severity, str) else "error",
                         "message": f.get("message", "")})
    return reported


def read_expected(document, path):
    if not isinstance(document, dict) or not isinstance(document.get("expected"), list):
        raise InputError(f"{path}: expected an object with an \"expected\" list")
    expected = []
    for i, e in enumerate(document["expected"]):
        where = f"{path}: expected finding {i + 1}"
        if not isinstance(e, dict):
            raise InputError(f"{where}: not an object")
        rule, axis = e.get("rule"), e.get("axis")
        first, last = e.get("first_frame"), e.get("last_frame")
        if not (isinstance(rule, str) and is_axis(axis) and is_frame(first) and is_frame(last)
                and first <= last):
            raise InputError(f"{where}: needs \"rule\", \"axis\" and 1 <= \"first_frame\" <= "
                             f"\"last_frame\": {json.dumps(e)[:200]}")
        expected.append({"rule": rule, "axis": axis, "first": first, "last": last,
                         "due": e.get("due_frame")})
    companions = document.get("companions", {})
    if not isinstance(companions, dict) or not all(
            isinstance(v, list) and all(isinstance(r, str) for r in v)
            for v in companions.values()):
        raise InputError(f"{path}: \"companions\" must map rule IDs to lists of rule IDs")
    return expected, companions


def match(expected, reported):
    """Pair each expected finding with a distinct reported one (same rule and axis, frame in
    the window).  Per (rule, axis), windows taken by their end, each given the earliest free
    frame in it: this pairs as many as any assignment can.  Returns (pairs, missing, rest)."""
    by_key = collections.defaultdict(list)
    for r in reported:
        by_key[(r["rule"], r["axis"])].append(r)
    for candidates in by_key.values():
        candidates.sort(key=lambda r: r["frame"])
    used, pairs, missing = set(), [], []
    for e in sorted(expected, key=lambda e: (e["last"], e["first"])):
        candidates = by_key.get((e["rule"], e["axis"]), [])
        hit = next((r for r in candidates
                    if id(r) not in used and e["first"] <= r["frame"] <= e["last"]), None)
        if hit is None:
            missing.append(e)
        else:
            used.add(id(hit))
            pairs.append((e, hit))
    rest = [r for r in reported if id(r) not in used]
    return pairs, missing, rest


def axis_text(axis):
    return "bus" if axis is None else f"axis {axis}"


def frames_text(frames, limit=8):
    shown = ", ".join(str(f) for f in frames[:limit])
    return shown + (f", ... ({len(frames)} in all)" if len(frames) > limit else "")


def check(reported, expected, companions, verbose=False, out=sys.stdout):
    pairs, missing, rest = match(expected, reported)
    injected = {e["rule"] for e in expected}
    allowed = {}
    for rule, others in companions.items():
        for other in others:
            allowed.setdefault(other, rule)
    tolerated = [r for r in rest if r["rule"] in allowed]
    unexpected = [r for r in rest if r["rule"] not in allowed]

    lines = []
    for e in sorted(missing, key=lambda e: (e["first"], e["rule"])):
        same = [r["frame"] for r in reported if r["rule"] == e["rule"] and r["axis"] == e["axis"]]
        other_axes = sorted({r["axis"] for r in reported if r["rule"] == e["rule"]
                             and r["axis"] != e["axis"]}, key=lambda a: (a is not None, a or 0))
        due = f", due {e['due']}" if is_frame(e["due"]) else ""
        note = (f"reported for this axis at frame(s) {frames_text(same)}" if same
                else "not reported for this axis")
        if other_axes:
            note += "; reported for " + ", ".join(axis_text(a) for a in other_axes)
        lines.append(f"- missing    {e['rule']:<8} {axis_text(e['axis']):<7} frames "
                     f"{e['first']}..{e['last']}{due}: {note}")
    for r in sorted(unexpected, key=lambda r: (r["frame"], r["rule"])):
        why = "" if r["rule"] in injected else " (rule not injected)"
        message = f": {r['message']}" if r["message"] else ""
        lines.append(f"+ unexpected {r['rule']:<8} {axis_text(r['axis']):<7} frame {r['frame']} "
                     f"{r['severity']}{why}{message}"[:200])
    if verbose:
        for e, r in sorted(pairs, key=lambda p: p[1]["frame"]):
            lines.append(f"  matched    {e['rule']:<8} {axis_text(e['axis']):<7} frame "
                         f"{r['frame']} in {e['first']}..{e['last']}")
        groups = collections.defaultdict(list)
        for r in tolerated:
            groups[(r["rule"], r["axis"])].append(r["frame"])
        for (rule, axis), frames in sorted(groups.items(), key=lambda g: min(g[1])):
            lines.append(f"  companion  {rule:<8} {axis_text(axis):<7} frame(s) "
                         f"{frames_text(frames)} (of {allowed[rule]})")
    ok = not missing and not unexpected
    print(f"check_findings: {'PASS' if ok else 'FAIL'}: {len(expected)} expected, "
          f"{len(pairs)} matched, {len(missing)} missing, {len(unexpected)} unexpected, "
          f"{len(tolerated)} companion(s)", file=out)
    for line in lines:
        print(line, file=out)
    return ok


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("report", help="ncservo validate --format json (or jsonl) output")
    p.add_argument("expected", help="gen_capture.py --findings output")
    p.add_argument("--capture", help="which capture of the report (index or path), "
                                     "when it holds several")
    p.add_argument("--verbose", "-v", action="store_true",
                   help="also list matched and companion findings")
    args = p.parse_args(argv)
    try:
        reported = read_reported(pick_capture(load_json(args.report), args.report, args.capture),
                                 args.report)
        expected, companions = read_expected(load_json(args.expected), args.expected)
    except InputError as e:
        print(f"check_findings: {e}", file=sys.stderr)
        return 2
    return 0 if check(reported, expected, companions, args.verbose) else 1


if __name__ == "__main__":
    sys.exit(main())
