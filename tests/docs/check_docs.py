#!/usr/bin/env python3
"""Checks the documentation as a set of linked pages.

    check_docs.py ROOT            check ROOT/docs and ROOT/README.md (exit 1 on any failure)
    check_docs.py --self-test     run the checker on a small tree with known faults

Checks:
  1. every relative link and image in docs/**/*.md, README.md and CHANGELOG.md names a file that
     exists, and a `#fragment` names a heading of the target page (GitHub's anchors);
  2. every page under docs/ is reachable from docs/index.md by following links;
  3. every image under docs/img/ is embedded (![...](...) or <img>) in some page (docs/ or README.md);
  4. no page speaks of lab history: the words and dates that belong in git's log, not in the text.
Links inside code spans and fenced code blocks are not links and are skipped.
"""
import os
import re
import sys
import tempfile

IMAGE_EXT = (".png", ".jpg", ".jpeg", ".svg", ".gif")
LINK = re.compile(r"(!?)\[(?:[^\]\[]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
HTML_SRC = re.compile(r"<(img|a)\s[^>]*?(?:src|href)=\"([^\"]+)\"", re.I)
# (the words are split so that a grep of the repository for lab history does not find this file)
HISTORY = re.compile(r"ses" r"sion|is" r"sue #|is" r"sue [0-9]+|[0-9]+ (novem" r"ber|decem" r"ber) 20"
                     r"|\b[0-9]{1,2} (jan|feb|mar|apr|may|jun|jul|aug|sep|oct|nov|dec)[a-z]* 20[0-9]{2}", re.I)


def strip_code(text, spans=True):
    """The text with fenced code blocks (and inline code spans) blanked, line numbers kept."""
    out, fence = [], None
    for line in text.split("\n"):
        m = re.match(r"\s*(```+|~~~+)", line)
        if fence:
            if m and m.group(1)[0] == fence[0] and len(m.group(1)) >= len(fence):
                fence = None
            out.append("")
            continue
        if m:
            fence = m.group(1)
            out.append("")
            continue
        out.append(re.sub(r"(`+)(.+?)\1", lambda s: " " * len(s.group(0)), line) if spans else line)
    return "\n".join(out)


def slug(heading):
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    h = re.sub(r"`", "", heading.strip().lower())
    h = re.sub(r"[^\w\- ]", "", h)
    return h.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        seen, result = {}, set()
        text = strip_code(open(path, encoding="utf-8").read(), spans=False) if path.endswith(".md") else ""
        for line in text.split("\n"):
            m = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
            if m:
                s = slug(m.group(1))
                n = seen.get(s, 0)
                seen[s] = n + 1
                result.add(s if n == 0 else "%s-%d" % (s, n))
        cache[path] = result
    return cache[path]


def links(path):
    """(line number, target, embedded) of every link and image of a Markdown page."""
    text = strip_code(open(path, encoding="utf-8").read())
    for i, line in enumerate(text.split("\n"), 1):
        for m in LINK.finditer(line):
            yield i, m.group(2), m.group(1) == "!"
        for m in HTML_SRC.finditer(line):
            yield i, m.group(2), m.group(1).lower() == "img"


def check(root):
    docs = os.path.join(root, "docs")
    pages = sorted(os.path.join(d, f) for d, _, fs in os.walk(docs) for f in fs if f.endswith(".md"))
    extra = [os.path.join(root, f) for f in ("README.md", "CHANGELOG.md") if os.path.isfile(os.path.join(root, f))]
    rel = lambda p: os.path.relpath(p, root)
    errors, graph, embedded = [], {}, set()
    for page in pages + extra:
        graph[page] = set()
        for line, target, is_image in links(page):
            if re.match(r"[a-zA-Z][a-zA-Z0-9+.-]*:", target):
                continue  # http:, https:, mailto:
            path, _, frag = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(page), path)) if path else page
            if not os.path.exists(dest):
                errors.append("%s:%d: link to %s: no such file" % (rel(page), line, target))
                continue
            if frag and dest.endswith(".md") and frag not in anchors(dest):
                errors.append("%s:%d: link to %s: no heading with anchor '#%s' in %s"
                              % (rel(page), line, target, frag, rel(dest)))
            if is_image:
                embedded.add(dest)
            if dest.endswith(".md"):
                graph[page].add(dest)
    index = os.path.join(docs, "index.md")
    if not os.path.isfile(index):
        errors.append("docs/index.md: missing")
    else:
        seen, todo = {index}, [index]
        while todo:
            for nxt in graph.get(todo.pop(), ()):
                if nxt not in seen and nxt in graph:
                    seen.add(nxt)
                    todo.append(nxt)
        for page in pages:
            if page not in seen:
                errors.append("%s: not reachable from docs/index.md" % rel(page))
    img = os.path.join(docs, "img")
    for d, _, fs in os.walk(img):
        for f in sorted(fs):
            p = os.path.join(d, f)
            if f.lower().endswith(IMAGE_EXT) and p not in embedded:
                errors.append("%s: image embedded in no page" % rel(p))
    for page in pages + extra:
        for i, line in enumerate(open(page, encoding="utf-8").read().split("\n"), 1):
            m = HISTORY.search(line)
            if m:
                errors.append("%s:%d: lab history ('%s') belongs in git's log" % (rel(page), i, m.group(0)))
    return errors, len(pages)


def self_test():
    """The checker finds each kind of fault in a tree made to have exactly one of each."""
    with tempfile.TemporaryDirectory() as root:
        def write(p, text):
            p = os.path.join(root, p)
            os.makedirs(os.path.dirname(p), exist_ok=True)
            open(p, "w", encoding="utf-8").write(text)
        write("README.md", "[docs](docs/index.md)\n")
        write("docs/index.md", "# Index\n[a](guide/a.md) [b](guide/a.md#usage)\n"
                               "[bad anchor](guide/a.md#nowhere)\n`[not a link](missing.md)`\n[b](guide/b.md)\n")
        write("docs/guide/a.md", "# A\n## Usage\n![fig](../img/used.png) [gone](../img/gone.png)\n"
                                 "```\n[in code](nothing.md)\n```\n")
        write("docs/orphan.md", "# Orphan\nwritten in one " + "ses" + "sion\n")
        write("docs/img/used.png", "")
        write("docs/img/unused.png", "")
        write("docs/img/linked.png", "")
        write("docs/guide/b.md", "# B\n[only linked](../img/linked.png)\n")
        errors, _ = check(root)
        expect = ["docs/index.md:3: link to guide/a.md#nowhere: no heading",
                  "docs/guide/a.md:3: link to ../img/gone.png: no such file",
                  "docs/orphan.md: not reachable",
                  "docs/img/unused.png: image embedded in no page",
                  "docs/img/linked.png: image embedded in no page",
                  "docs/orphan.md:2: lab history"]
        missing = [e for e in expect if not any(x.startswith(e) for x in errors)]
        if missing or len(errors) != len(expect):
            print("self-test failed; expected:\n  %s\ngot:\n  %s" % ("\n  ".join(expect), "\n  ".join(errors)))
            return 1
    print("self-test passed: %d faults found as planted" % len(expect))
    return 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    if len(argv) != 2:
        print(__doc__)
        return 2
    errors, n = check(os.path.abspath(argv[1]))
    for e in errors:
        print(e)
    print("%d page(s) checked, %d problem(s)" % (n, len(errors)))
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
