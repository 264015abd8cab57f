#!/usr/bin/env python3
"""Normalise an `ncservo validate --format json` report for golden comparison.

Reads the report on standard input and writes it with what depends on where and with which
build it ran left out (the capture's path, the tool's version), sorted keys, 2-space indent.
"""
import json
import sys

report = json.load(sys.stdin)
report["tool"].pop("version", None)
for capture in report["captures"]:
    capture.pop("path", None)
json.dump(report, sys.stdout, indent=2, sort_keys=True)
sys.stdout.write("\n")
