#!/usr/bin/env python3
"""Code layout of C++ source trees: files above a line limit and function bodies above a line limit.

  python3 tools/code_layout.py [--max-file 600] [--max-function 80] [--exclude GLOB ...] [DIR ...]
  python3 tools/code_layout.py --self-test

Every .cpp and .h file below each DIR (default: liggghts_mpm/ and laser/) is checked. A function is
a brace block opened at nesting depth 0 (or inside namespace, class and struct blocks) whose header
contains '('; class, struct, enum and namespace blocks are descended into, not counted. Its length
counts from the header line to the closing brace. Comments, string literals and preprocessor lines
are skipped; a preprocessor line also ends a header, so that a style macro such as
`FixStyle(name, Class)` before `#else` is not read as the header of the block that follows.
Files matching an --exclude glob (on the path relative to its DIR, e.g. 'mpm/projection*.cpp') are
listed with '(excluded)' but do not fail the check. Exit status 1 when anything else is above a limit.
Standard library only (CTest runs it with the system Python).
"""
import argparse
import fnmatch
import os
import re
import sys
import tempfile

BLOCK_KEYWORDS = re.compile(r"^\s*(namespace|class|struct|enum|union|extern)\b")
TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


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
    continued = False  # the previous line was a preprocessor line ending in a backslash
    with open(path) as fh:
        lines = fh.readlines()
    for no, raw in enumerate(lines, 1):
        if not state["block"] and (continued or raw.lstrip().startswith("#")):
            continued = raw.rstrip().endswith("\\")
            header, header_line = "", 0
            continue
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


def sources(top):
    """The .cpp and .h files below top, as paths relative to top, sorted."""
    out = []
    for root, dirs, files in os.walk(top):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        for name in files:
            if name.endswith((".cpp", ".h")):
                out.append(os.path.relpath(os.path.join(root, name), top))
    return sorted(out)


def check(dirs, max_file, max_function, exclude=(), out=sys.stdout):
    """Prints one line per file (and one per function above the limit); returns the number of
    violations outside the excluded files."""
    bad = 0
    for top in dirs:
        label = os.path.basename(os.path.normpath(top))
        for rel in sources(top):
            path = os.path.join(top, rel)
            excluded = any(fnmatch.fnmatch(rel, g) for g in exclude)
            with open(path) as fh:
                n = sum(1 for _ in fh)
            funcs = list(functions(path))
            longest = max(funcs, key=lambda f: f[2], default=("-", 0, 0))
            flag, count = "", 0
            if n > max_file:
                flag += " FILE>%d" % max_file
                count += 1
            for fn, start, length in funcs:
                if length > max_function:
                    print("%s/%s:%d: function %s has %d lines (> %d)%s"
                          % (label, rel, start, fn, length, max_function, " (excluded)" if excluded else ""), file=out)
                    count += 1
            if excluded and count:
                flag += " (excluded)"
            elif count:
                bad += count
            print("%-36s %5d lines, longest function %s (%d lines)%s"
                  % (label + "/" + rel, n, longest[0], longest[2], flag), file=out)
    return bad


def self_test():
    """The checker on a tree with planted faults: a long file, a long function, a long function
    inside a namespace and a class, and a style macro before a class (not a function)."""
    with tempfile.TemporaryDirectory() as d:
        os.makedirs(os.path.join(d, "sub"))
        body = "\n".join("  x += %d;" % i for i in range(85))
        with open(os.path.join(d, "sub", "long_func.cpp"), "w") as f:
            f.write("namespace a {\nint f(int x)\n{\n%s\n  return x;\n}\n}\n" % body)
        with open(os.path.join(d, "long_file.h"), "w") as f:
            f.write("// x\n" * 601)
        with open(os.path.join(d, "in_class.h"), "w") as f:
            f.write("struct S {\n  int g(int x) {\n%s\n    return x; }\n};\n" % body)
        with open(os.path.join(d, "style.h"), "w") as f:
            f.write("#ifdef FIX_CLASS\nFixStyle(a/b, FixAB)\n#else\n#define X \\\n  {\n"
                    "namespace N {\nclass FixAB {\n%s\n};\n}\n#endif\n" % "\n".join("  int m%d;" % i for i in range(90)))
        with open(os.path.join(d, "short.cpp"), "w") as f:
            f.write("int h() { const char *s = \"{\"; return s[0]; }  // {\n/* { */\n")
        sink = open(os.devnull, "w")
        found = check([d], 600, 80, out=sink)
        excluded = check([d], 600, 80, exclude=["sub/*", "long_file.h", "in_class.h"], out=sink)
        ok = found == 3 and excluded == 0
        print("self-test: %d violations found (3 planted), %d with the planted files excluded: %s"
              % (found, excluded, "ok" if ok else "FAIL"))
        return 0 if ok else 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="*", default=[os.path.join(TOP, "liggghts_mpm"), os.path.join(TOP, "laser")])
    ap.add_argument("--max-file", type=int, default=600)
    ap.add_argument("--max-function", type=int, default=80)
    ap.add_argument("--exclude", action="append", default=[], metavar="GLOB")
    ap.add_argument("--self-test", action="store_true")
    a = ap.parse_args()
    if a.self_test:
        return self_test()
    bad = check(a.dirs, a.max_file, a.max_function, a.exclude)
    print("%d violation(s)%s" % (bad, " outside the excluded files" if a.exclude else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
