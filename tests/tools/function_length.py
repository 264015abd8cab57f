#!/usr/bin/env python3
"""Fails when a function in validator/ or plugin/ is longer than 100 lines, naming each with its
file, line and length; a function counts from the line of its name to its closing brace.

A brace-counting heuristic, not a parser: comments, strings and preprocessor lines are blanked,
then every brace block opened outside a function (in a namespace, a class, extern "C") is a
definition, a function (or a lambda) when a parameter list comes before its brace. A variable's
initialiser (`kRules{{`, `kFields[] = {`) is a data table, as long as its rows, and not measured;
a function that holds a table, or must stay long for now, is in ALLOWED with the reason.
Usage: function_length.py SOURCE_DIR"""
import os
import re
import sys

LIMIT = 100
FOLDERS = ("validator", "plugin")

# (file under SOURCE_DIR, function) -> why it may be longer than LIMIT.
ALLOWED = {
    ("validator/sim/src/faults.cpp", "faultRecipes"):
        "a data table: one fault recipe per rule",
    ("validator/sim/src/incident_plan.cpp", "incidentRows"):
        "a data table: one simulated incident per cause",
}

SCOPE = re.compile(r"(template\s*<.*>\s*)?(namespace\b|extern\b|(class|struct|union|enum)\b)", re.S)
# A macro's use on lines of its own before a definition (NCSERVO_WS_DESCRIBE_PLUGIN(...)).
MACRO_LINES = re.compile(r"^(\s*[A-Z][A-Z0-9_]*\([^;{}]*\)\s*\n)+")
NOT_NAMES = {"decltype", "alignas", "__attribute__", "noexcept", "requires", "sizeof"}
# A constructor's initialiser list has begun: `Foo::Foo(int x) : x_`.
INITIALISER_LIST = re.compile(r"\)\s*:[^:]")


def blanked(text):
    """The text with comments, literals and preprocessor lines as spaces, its newlines kept."""
    out = []
    i, n = 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if c == "\n":
            line_start = True
            out.append(c)
            i += 1
            continue
        if line_start and c == "#":  # a preprocessor line and its continuations
            end = i
            while end < n and (text[end] != "\n" or text[end - 1] == "\\"):
                end += 1
        elif text.startswith("//", i):
            end = text.find("\n", i)
            end = n if end < 0 else end
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
        elif text.startswith('R"', i) and not (i and re.match(r"\w", text[i - 1])):
            delimiter = text[i + 2:text.find("(", i + 2)]
            end = text.find(")" + delimiter + '"', i)
            end = n if end < 0 else end + len(delimiter) + 2
        elif c == '"' or (c == "'" and not (i and re.match(r"[0-9A-Fa-f]", text[i - 1]))):
            end = i + 1  # (a ' after a digit separates digits)
            while end < n and text[end] != c:
                end += 2 if text[end] == "\\" else 1
            end += 1
        else:
            if not c.isspace():
                line_start = False
            out.append(c)
            i += 1
            continue
        out.append(re.sub(r"[^\n]", " ", text[i:end]))
        i = end
    return "".join(out)


def matching_brace(text, at):
    depth = 0
    for j in range(at, len(text)):
        if text[j] == "{":
            depth += 1
        elif text[j] == "}":
            depth -= 1
            if depth == 0:
                return j
    return len(text) - 1


def function_name(header):
    """The name before the header's parameter list (its first parenthesis outside parentheses and
    template arguments after a name), or None when it has none: a variable's initialiser."""
    if re.search(r"=\s*$", header):
        return None
    lambda_at = re.search(r"([\w:]+)\s*=\s*\[", header)
    if lambda_at:
        return lambda_at.group(1)
    depth = 0
    for at, c in enumerate(header):
        if c == "(" and depth == 0:
            name = re.search(r"(operator\W+|[~\w:]+)\s*$", header[:at])
            if name and name.group(1) not in NOT_NAMES:
                return name.group(1)
        if c in "(<":
            depth += 1
        elif c in ")>" and depth > 0:
            depth -= 1
    return None


def functions(text):
    """(name, first line, last line) of every function defined outside another."""
    header_start = 0  # where the text before the next definition begins
    found = []
    i = 0
    while i < len(text):
        c = text[i]
        if c in ";}":  # (a function's body is skipped whole: this closes a namespace or a class)
            header_start = i + 1
        if c != "{":
            i += 1
            continue
        raw = MACRO_LINES.sub("", text[header_start:i].lstrip("\n"))
        header = raw.strip()
        if INITIALISER_LIST.search(header) and re.match(r"[\w>]", text[i - 1]):
            i = matching_brace(text, i) + 1  # a member's `x_{y}` in the list, not the body
            continue
        if not header or SCOPE.match(header):
            header_start = i + 1
            i += 1
            continue
        end = matching_brace(text, i)
        name = function_name(header)
        if name is not None:
            first = text.count("\n", 0, i - len(raw.lstrip())) + 1
            found.append((name, first, text.count("\n", 0, end) + 1))
        header_start = i = end + 1
    return found


def main():
    root = sys.argv[1]
    too_long, allowed_seen = [], set()
    for top in FOLDERS:
        for folder, _, names in sorted(os.walk(os.path.join(root, top))):
            for file_name in sorted(n for n in names if n.endswith((".cpp", ".hpp", ".h", ".c"))):
                path = os.path.join(folder, file_name)
                rel = os.path.relpath(path, root)
                with open(path, encoding="utf-8") as f:
                    text = blanked(f.read())
                for name, first, last in functions(text):
                    length = last - first + 1
                    if length <= LIMIT:
                        continue
                    if (rel, name) in ALLOWED:
                        allowed_seen.add((rel, name))
                    else:
                        too_long.append(f"{rel}:{first}: {name}: {length} lines")
    stale = sorted(f"{rel} {name}" for rel, name in ALLOWED.keys() - allowed_seen)
    if stale:
        print("in ALLOWED but no longer over the limit (remove them): " + ", ".join(stale))
    if too_long:
        print(f"functions over {LIMIT} lines (split them into functions that each do one thing):")
        print("\n".join(too_long))
    if stale or too_long:
        sys.exit(1)
    print(f"function_length: no function over {LIMIT} lines in {' and '.join(FOLDERS)} but the "
          f"{len(ALLOWED)} allowed")


if __name__ == "__main__":
    main()
