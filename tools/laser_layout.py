#!/usr/bin/env python3
"""Code layout of laser/: files above a line limit and function bodies above a line limit.

  tools/python tools/laser_layout.py [--max-file 600] [--max-function 80] [DIR]

A function is a brace block opened at nesting depth 0 (or depth 1 inside a namespace)
whose header line contains '(' (class, struct, enum and namespace blocks are descended
into, not counted). Its length counts from the header line to the closing brace.
Exit status 1 when anything is above a limit.
"""
import argparse
import os
import re
import sys

BLOCK_KEYWORDS = re.compile(r"^\s*(namespace|class|struct|enum|union|extern)\b")


def strip(line, state):
    """Removes comments and string/char literals; state carries a block comment."""
    out, i = [], 0
    while i < len(line):
        if state["block"]:
            j = line.find("*/", i)
            if j < 0:
                return "".join(out)
            state["block"], i = False, j + 2
            continue
        c = line[i]
        if line.startswith("//", i):
            break
        if line.startswith("/*", i):
            state["block"], i = True, i + 2
            continue
        if c in "\"'":
            j = i + 1
            while j < len(line) and line[j] != c:
                j += 2 if line[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def functions(path):
    """Yields (name, first line, length) of every function body in the file."""
    state = {"block": False}
    stack = []  # entries: (kind, first line, header); kind "scope", "func" or "inner"
    header, header_line = "", 0
    with open(path) as fh:
        lines = fh.readlines()
    for no, raw in enumerate(lines, 1):
        for ch in strip(raw, state) + " ":
            if ch == "{":
                text = header.strip()
                if any(kind != "scope" for kind, _, _ in stack):
                    stack.append(("inner", no, text))
                elif BLOCK_KEYWORDS.match(text) or "(" not in text or text.endswith("="):
                    stack.append(("scope", no, text))
                else:
                    stack.append(("func", header_line or no, text))
                header, header_line = "", 0
            elif ch == "}":
                if stack:
                    kind, start, text = stack.pop()
                    if kind == "func":
                        name = re.findall(r"([~\w:]+)\s*\(", text)
                        yield (name[0] if name else text[:40]), start, no - start + 1
                header, header_line = "", 0
            elif ch == ";":
                header, header_line = "", 0
            else:
                if not header.strip() and not ch.isspace():
                    header_line = no
                header += ch


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir", nargs="?", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "laser"))
    ap.add_argument("--max-file", type=int, default=600)
    ap.add_argument("--max-function", type=int, default=80)
    a = ap.parse_args()
    bad = 0
    for name in sorted(os.listdir(a.dir)):
        if not name.endswith((".cpp", ".h")):
            continue
        path = os.path.join(a.dir, name)
        with open(path) as fh:
            n = sum(1 for _ in fh)
        longest = max((f for f in functions(path)), key=lambda f: f[2], default=("-", 0, 0))
        flag = ""
        if n > a.max_file:
            flag += " FILE>%d" % a.max_file
            bad += 1
        for fn, start, length in functions(path):
            if length > a.max_function:
                print("%s:%d: function %s has %d lines (> %d)" % (name, start, fn, length, a.max_function))
                bad += 1
        print("%-24s %5d lines, longest function %s (%d lines)%s" % (name, n, longest[0], longest[2], flag))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
