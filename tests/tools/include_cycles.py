#!/usr/bin/env python3
"""Fails when an include runs upward through the layers, or when modules include each other in a
cycle. The layers are validator/'s folders (README "Layers"); a file may include headers of its
own folder and of folders ranked below it, never above it nor beside it (two folders of one rank
stay independent). A module is a header and its source file of the same name; module A depends on
B when A's header or source includes B's header.
Usage: include_cycles.py SOURCE_DIR"""
import os
import re
import sys

# folder (under the source directory) -> rank; lower ranks are the layers below
RANKS = {
    "validator/base": 0,
    "validator/wire": 1,
    "validator/protocol": 2,
    "validator/layout": 3,
    "validator/model": 4,
    "validator/rules": 5,
    "validator/config": 6,
    "validator/incidents": 6,
    "validator/pipeline": 7,
    "validator/capture": 8,
    "validator/report": 9,
    "validator/sim": 9,
    "validator/telemetry": 10,
    "validator/cli": 11,
    "plugin": 11,
}

root = sys.argv[1]
include = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
files = []
for top in ("validator", "plugin"):
    for dirpath, _, names in os.walk(os.path.join(root, top)):
        files += [os.path.join(dirpath, n) for n in names if n.endswith((".hpp", ".h", ".cpp"))]


def folder(path):
    rel = os.path.relpath(path, root)
    for name in sorted(RANKS, key=len, reverse=True):
        if rel.startswith(name + "/"):
            return name
    return None


def module(path):
    return os.path.splitext(os.path.basename(path))[0]


unranked = sorted({os.path.relpath(p, root) for p in files if folder(p) is None})
if unranked:
    print("files in no ranked folder (add the folder to RANKS): " + ", ".join(unranked))
    sys.exit(1)

header = {}  # include spelling -> path
for path in files:
    if path.endswith((".hpp", ".h")):
        if "/include/" in path:
            header[path.split("/include/", 1)[1]] = path
        header.setdefault(os.path.basename(path), path)

edges, upward = {}, []
for path in files:
    with open(path, encoding="utf-8") as f:
        spelled = include.findall(f.read())
    here = folder(path)
    deps = set()
    for name in spelled:
        target = header.get(name)
        if target is None:
            continue
        there = folder(target)
        if there != here and RANKS[there] >= RANKS[here]:
            upward.append(f"{os.path.relpath(path, root)} includes {name}: {here} (rank "
                          f"{RANKS[here]}) may not include {there} (rank {RANKS[there]})")
        deps.add(module(target))
    edges.setdefault(module(path), set()).update(deps - {module(path)})

if upward:
    print("\n".join(upward))
    sys.exit(1)

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
print(f"no upward include among {len(files)} files in {len(RANKS)} layers; "
      f"no include cycle among {len(edges)} modules")
