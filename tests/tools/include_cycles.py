#!/usr/bin/env python3
"""Fails when modules of the project include each other in a cycle (issue 12: one home per
concept). A module is a header and its source file of the same name (rules.hpp + rules.cpp);
module A depends on B when A's header or source includes B's header.
Usage: include_cycles.py SOURCE_DIR"""
import os
import re
import sys

root = sys.argv[1]
include = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
files = []
for top in ("validator", "plugin"):
    for dirpath, _, names in os.walk(os.path.join(root, top)):
        files += [os.path.join(dirpath, n) for n in names if n.endswith((".hpp", ".h", ".cpp"))]


def module(path):
    return os.path.splitext(os.path.basename(path))[0]


header_module = {}  # include spelling -> module
for path in files:
    if path.endswith((".hpp", ".h")):
        spelled = path.split("/include/", 1)[1] if "/include/" in path else os.path.basename(path)
        header_module[spelled] = module(path)
        header_module.setdefault(os.path.basename(path), module(path))

edges = {}
for path in files:
    with open(path, encoding="utf-8") as f:
        deps = {header_module[i] for i in include.findall(f.read()) if i in header_module}
    edges.setdefault(module(path), set()).update(deps - {module(path)})

state, stack = {}, []


def visit(node):
    state[node] = 1
    stack.append(node)
    for nxt in sorted(edges.get(node, ())):
        if state.get(nxt) == 1:
            print("include cycle: " + " -> ".join(stack[stack.index(nxt):] + [nxt]))
            sys.exit(1)
        if nxt not in state:
            visit(nxt)
    stack.pop()
    state[node] = 2


for node in sorted(edges):
    if node not in state:
        visit(node)
print(f"no include cycle among {len(edges)} modules")
