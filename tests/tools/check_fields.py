#!/usr/bin/env python3
"""Compare decoded ncservo fields with the truth written by gen_capture.py.

    check_fields.py TRUTH.jsonl OUTPUT.tsv
        OUTPUT from: tshark -r CAP -T fields -E occurrence=a -E separator=/t -E aggregator=,
                     -e frame.number -e ncservo.ssp ... (the --fields, in that order)
    check_fields.py --format ncservo-csv TRUTH.jsonl OUTPUT.csv
        OUTPUT from: ncservo decode (one row per axis per cycle)
    check_fields.py --self-test TRUTH.jsonl

Exit status 0 when everything matches, 1 otherwise; the first mismatches are printed.
"""

import argparse
import csv
import json
import math
import os
import sys
import tempfile

DEFAULT_FIELDS = ("ssp", "scw", "ext_code", "actpos", "ssw", "sew", "msg_code", "msg_data")
RX_KEYS = ("ssp", "scw", "ext_code")
TX_KEYS = ("actpos", "ssw", "sew", "msg_code", "msg_data",
           "ext_data1", "ext_data2", "ext_data3", "ext_data4")
HEX_KEYS = ("scw", "ssw", "sew")
FLOAT_KEYS = ("msg_data", "ext_data1", "ext_data2", "ext_data3", "ext_data4")
# tshark 4.0 prints FT_FLOAT with "%.6g" (FLT_DIG digits): six significant digits are off
# by at most half a unit of the sixth digit, a relative error of 5e-6.
FLOAT_REL_TOL = 5e-6
FLOAT_ABS_TOL = 1e-30
SHOWN_MISMATCHES = 20


def field_key(name):
    """'ncservo.ssw' and 'ssw' both name the truth key 'ssw'."""
    key = name[len("ncservo."):] if name.startswith("ncservo.") else name
    if key not in RX_KEYS + TX_KEYS:
        raise SystemExit(f"check_fields: unknown field {name!r}")
    return key


def load_truth(path):
    with open(path, encoding="ascii") as f:
        return [json.loads(line) for line in f if line.strip()]


def format_value(key, value):
    """The value the way tshark's -T fields prints it."""
    if key in HEX_KEYS:
        return f"0x{value:08x}"
    if key in FLOAT_KEYS:
        return f"{value:.6g}"
    return str(value)


def parse_value(key, text):
    """A printed value, or the text itself when it does not parse (it then never matches)."""
    try:
        if key in FLOAT_KEYS:
            return float(text)
        return int(text, 16) if text.lower().startswith("0x") else int(text)
    except ValueError:
        return text


def same_value(key, expected, got):
    if key in FLOAT_KEYS and isinstance(got, float):
        return math.isclose(got, expected, rel_tol=FLOAT_REL_TOL, abs_tol=FLOAT_ABS_TOL)
    return type(got) is int and got == expected


class Report:
    """Counts comparisons and keeps the first mismatches for printing."""

    def __init__(self):
        self.checked = 0
        self.failed = 0
        self.shown = []

    def fail(self, message):
        self.failed += 1
        if len(self.shown) < SHOWN_MISMATCHES:
            self.shown.append(message)

    def compare(self, frame, key, expected, got_texts, where=""):
        """expected: truth values; got_texts: printed values ("" or None = absent)."""
        self.checked += 1
        got = [parse_value(key, t) for t in got_texts]
        if len(got) == len(expected) and all(map(lambda e, g: same_value(key, e, g),
                                                 expected, got)):
            return
        shown_expected = ",".join(format_value(key, v) for v in expected)
        self.fail(f"frame {frame}{where} ncservo.{key}: expected [{shown_expected}] "
                  f"got [{','.join(got_texts)}]")

    def print(self, out=sys.stdout):
        for line in self.shown:
            print(line, file=out)
        if self.failed > len(self.shown):
            print(f"... and {self.failed - len(self.shown)} more", file=out)
        verdict = "OK" if self.ok() else "FAIL"
        print(f"{verdict}: {self.checked} comparisons, {self.failed} mismatches", file=out)

    def ok(self):
        return self.failed == 0


# --- tshark -T fields output ---
def read_tsv(path, n_fields):
    """frame number -> list of columns (each the raw text of one field)."""
    rows = {}
    with open(path, encoding="utf-8") as f:
        for line_number, line in enumerate(f, 1):
            columns = line.rstrip("\r\n").split("\t")
            if columns[0] == "frame.number":  # a header row (-E header=y)
                continue
            if len(columns) != 1 + n_fields:
                raise SystemExit(f"check_fields: {path}:{line_number}: {len(columns)} columns, "
                                 f"expected {1 + n_fields}")
            rows[int(columns[0])] = columns[1:]
    return rows


def check_tsv(truth, path, keys):
    report = Report()
    rows = read_tsv(path, len(keys))
    for record in truth:
        frame = record["frame"]
        columns = rows.pop(frame, None)
        if columns is None:
            report.fail(f"frame {frame}: missing from the output")
            continue
        for key, text in zip(keys, columns):
            expected = [axis[key] for axis in record["axes"] if key in axis]
            report.compare(frame, key, expected, text.split(",") if text else [])
    for frame in sorted(rows):
        report.fail(f"frame {frame}: in the output but not in the truth")
    return report


# --- ncservo decode CSV ---
def expected_rows(truth):
    """frame number -> truth axes for the frames that carry a CSV row.

    A cycle's row is on its returned copy, or on the master copy when none was captured;
    the truth lists a returned copy right after its master copy.
    """
    expected = {}
    for i, record in enumerate(truth):
        following = truth[i + 1] if i + 1 < len(truth) else None
        if record["copy"] == "returned" or not (following and following["copy"] == "returned"):
            expected[record["frame"]] = record["axes"]
    return expected


def read_csv_rows(path, keys):
    """frame number -> rows (dicts) of that frame, in axis order."""
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        missing = [c for c in ("frame", "axis") + tuple(keys) if c not in reader.fieldnames]
        if missing:
            raise SystemExit(f"check_fields: {path}: no column {', '.join(missing)}")
        rows = {}
        for row in reader:
            rows.setdefault(int(row["frame"]), []).append(row)
    for frame_rows in rows.values():
        frame_rows.sort(key=lambda row: int(row["axis"]))
    return rows


def check_csv(truth, path, keys, axis_base):
    report = Report()
    rows = read_csv_rows(path, keys)
    for frame, axes in expected_rows(truth).items():
        frame_rows = rows.pop(frame, None)
        if frame_rows is None:
            report.fail(f"frame {frame}: no rows in the output")
            continue
        report.checked += 1
        got_axes = [int(row["axis"]) for row in frame_rows]
        want_axes = [axis["axis"] + axis_base for axis in axes]
        if got_axes != want_axes:
            report.fail(f"frame {frame}: rows for axes {got_axes}, expected {want_axes}")
            continue
        for axis, row in zip(axes, frame_rows):
            for key in keys:
                expected = [axis[key]] if key in axis else []
                text = row[key]
                report.compare(frame, key, expected, [text] if text else [],
                               f" axis {row['axis']}")
    for frame in sorted(rows):
        report.fail(f"frame {frame}: rows in the output but no such cycle in the truth")
    return report


def csv_keys(path, requested):
    """The fields to compare in a CSV: the requested ones, else every known column."""
    if requested:
        return requested
    with open(path, newline="", encoding="utf-8") as f:
        header = next(csv.reader(f), [])
    present = [key for key in RX_KEYS + TX_KEYS if key in header]
    return present if set(DEFAULT_FIELDS) <= set(present) else list(DEFAULT_FIELDS)


# --- self-test: fabricated outputs must pass, perturbed ones must fail ---
def fabricate_tsv(truth, keys, path, skip_frame=None):
    with open(path, "w", encoding="utf-8") as f:
        for record in truth:
            if record["frame"] == skip_frame:
                continue
            columns = [str(record["frame"])]
            for key in keys:
                values = [format_value(key, axis[key]) for axis in record["axes"] if key in axis]
                columns.append(",".join(values))
            f.write("\t".join(columns) + "\n")


def fabricate_csv(truth, keys, path):
    with open(path, "w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(["frame", "time", "axis", "name"] + list(keys))
        for frame, axes in expected_rows(truth).items():
            for axis in axes:
                cells = [format_value(key, axis[key]) if key in axis else "" for key in keys]
                writer.writerow([frame, "0", axis["axis"], f"axis{axis['axis']}"] + cells)


def altered(truth, frame, alter):
    """A copy of the truth where alter(axis 0 of the frame) changed something."""
    copy = json.loads(json.dumps(truth))
    alter(next(r for r in copy if r["frame"] == frame)["axes"][0])
    return copy


def self_test(truth_path):
    truth = load_truth(truth_path)
    returned = next((r["frame"] for r in truth if r["copy"] == "returned"), None)
    master = next((r["frame"] for r in truth if r["copy"] == "master"), None)
    any_frame = truth[0]["frame"]
    row_frame = next(iter(expected_rows(truth)))  # a frame that has CSV rows
    keys = list(RX_KEYS + TX_KEYS)
    cases = []  # (name, report, should pass)
    with tempfile.TemporaryDirectory() as tmp:
        tsv, out_csv = os.path.join(tmp, "out.tsv"), os.path.join(tmp, "out.csv")

        def tsv_case(name, fabricated, should_pass, skip_frame=None):
            fabricate_tsv(fabricated, keys, tsv, skip_frame)
            cases.append((name, check_tsv(truth, tsv, keys), should_pass))

        def csv_case(name, fabricated, should_pass):
            fabricate_csv(fabricated, keys, out_csv)
            cases.append((name, check_csv(truth, out_csv, keys, 0), should_pass))

        tsv_case("tsv as tshark prints it", truth, True)
        tsv_case("tsv with one SCW bit flipped",
                 altered(truth, any_frame, lambda a: a.update(scw=a["scw"] ^ 0x400)), False)
        tsv_case("tsv missing a frame", truth, False, skip_frame=any_frame)
        if returned:
            tsv_case("tsv with one float off",
                     altered(truth, returned, lambda a: a.update(msg_data=a["msg_data"] + 0.01)),
                     False)
        if master:
            tsv_case("tsv with an SSW on a master copy",
                     altered(truth, master, lambda a: a.update(ssw=2)), False)
        csv_case("ncservo csv", truth, True)
        csv_case("ncservo csv with an ext code off by one",
                 altered(truth, row_frame, lambda a: a.update(ext_code=a["ext_code"] + 1)), False)
        if returned:
            csv_case("ncservo csv with ActPos off by one",
                     altered(truth, returned, lambda a: a.update(actpos=a["actpos"] + 1)), False)
    good = True
    for name, report, should_pass in cases:
        right = report.ok() == should_pass
        good &= right
        outcome = "passes" if report.ok() else f"fails ({report.shown[0]})"
        print(f"{'ok ' if right else 'BAD'} {name}: {outcome}")
    print("self-test " + ("passed" if good else "FAILED"))
    return 0 if good else 1


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("truth", help="JSON Lines truth from gen_capture.py --truth")
    p.add_argument("output", nargs="?", help="tshark fields output or ncservo decode CSV")
    p.add_argument("--format", choices=("tshark-fields", "ncservo-csv"), default="tshark-fields")
    p.add_argument("--fields", help="comma-separated fields after frame.number "
                   f"(default {','.join('ncservo.' + k for k in DEFAULT_FIELDS)}; "
                   "for a CSV, every known column)")
    p.add_argument("--axis-base", type=int, default=0,
                   help="number of the first axis in the CSV's axis column (default 0)")
    p.add_argument("--self-test", action="store_true",
                   help="check this script against outputs fabricated from TRUTH")
    args = p.parse_args(argv)
    if not args.self_test and not args.output:
        p.error("an OUTPUT file is needed")
    return args


def main(argv=None):
    args = parse_args(argv)
    if args.self_test:
        return self_test(args.truth)
    requested = [field_key(f) for f in args.fields.split(",")] if args.fields else None
    truth = load_truth(args.truth)
    if args.format == "ncservo-csv":
        report = check_csv(truth, args.output, csv_keys(args.output, requested), args.axis_base)
    else:
        report = check_tsv(truth, args.output, requested or list(DEFAULT_FIELDS))
    report.print()
    return 0 if report.ok() else 1


if __name__ == "__main__":
    sys.exit(main())
