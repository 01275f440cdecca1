#!/usr/bin/env python3
"""Fails on a broken link or image in the book (docs/src) or the README.

mdBook renders a chapter with a link to a missing file or heading without a word, so
this resolves every relative link itself:

- `[text](target)`, `![alt](target)`, `[label]: target` and `<a href>`/`<img src>`
  in every docs/src/**/*.md, outside code blocks and code spans;
- a target must be a file inside docs/src (the book is built from there alone: a link
  to ../../data/README.md works on GitHub and is dead in the book);
- a `#anchor` must name a heading of its page by mdBook's id rule (0.5: the heading's
  text, markup removed, lowercased, spaces to `-`, anything neither alphanumeric nor
  `_`/`-` dropped, a repeated id numbered `-1`, `-2`, ...);
- every chapter file is listed in SUMMARY.md (mdBook skips one that is not);
- README.md's relative links must name files of the repository, and its anchors into
  the book headings that exist.

Prints `file:line: what is wrong` for each and exits 1, or says how much it checked.
Usage: python3 scripts/check_book_links.py [REPO_ROOT]
"""
import os
import re
import sys
from urllib.parse import unquote

ROOT = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
SRC = os.path.join(ROOT, "docs", "src")

INLINE = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]*)>?(?:\s+\"[^\"]*\")?\s*\)")
REFDEF = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+.*)?$")
HTML = re.compile(r"<(?:a|img)\b[^>]*?\b(?:href|src)\s*=\s*[\"']([^\"']*)[\"']", re.I)
FENCE = re.compile(r"^\s{0,3}(```+|~~~+)")
HEADING = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
CODE_SPAN = re.compile(r"(`+)(.+?)\1")


def prose_lines(path):
    """(line number, text) of the lines outside fenced code, code spans blanked."""
    fence = None
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            m = FENCE.match(line)
            if m:
                mark = m.group(1)[0] * 3
                if fence is None:
                    fence = mark
                    continue
                if mark == fence:
                    fence = None
                    continue
            if fence is None:
                yield n, line.rstrip("\n")


def heading_id(text):
    """mdBook's id of a heading: markup and code ticks dropped, then normalized."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)  # a link keeps its text
    text = re.sub(r"<[^>]+>", "", text)
    text = text.replace("`", "").replace("*", "").replace("\\", "")
    text = text.replace("&lt;", "").replace("&gt;", "").replace("&amp;", "")
    out = []
    for ch in text.strip().lower():
        if ch.isalnum() or ch in "_-":
            out.append(ch)
        elif ch.isspace():
            out.append("-")
    return "".join(out)


_anchor_cache = {}


def anchors(path):
    if path not in _anchor_cache:
        seen = {}
        ids = set()
        for _, line in prose_lines(path):
            m = HEADING.match(line)
            if not m:
                continue
            base = heading_id(m.group(2))
            k = seen.get(base, 0)
            ids.add(base if k == 0 else f"{base}-{k}")
            seen[base] = k + 1
        with open(path, encoding="utf-8") as f:  # explicit <a id=...> / {#id}
            text = f.read()
        ids.update(re.findall(r"<a\s+(?:id|name)\s*=\s*[\"']([^\"']+)", text))
        ids.update(re.findall(r"\{#([A-Za-z0-9_-]+)\}", text))
        _anchor_cache[path] = ids
    return _anchor_cache[path]


def targets(path):
    for n, line in prose_lines(path):
        plain = CODE_SPAN.sub(lambda m: " " * len(m.group(0)), line)
        for rx in (INLINE, HTML):
            for m in rx.finditer(plain):
                yield n, m.group(1)
        m = REFDEF.match(plain)
        if m:
            yield n, m.group(1)


def external(t):
    return re.match(r"^[a-z][a-z0-9+.-]*:", t, re.I) is not None


def check_file(path, inside_book, errors):
    rel = os.path.relpath(path, ROOT)
    count = 0
    for n, t in targets(path):
        if not t or external(t):
            continue
        count += 1
        where = f"{rel}:{n}"
        file_part, _, anchor = t.partition("#")
        file_part = unquote(file_part)
        dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) if file_part else path
        if inside_book and not (dest + os.sep).startswith(SRC + os.sep):
            errors.append(f"{where}: '{t}' leaves docs/src, so it is dead in the built book")
            continue
        if not os.path.exists(dest):
            errors.append(f"{where}: '{t}': no such file {os.path.relpath(dest, ROOT)}")
            continue
        if anchor and dest.endswith(".md") and anchor not in anchors(dest):
            errors.append(f"{where}: '{t}': {os.path.relpath(dest, ROOT)} has no heading with id '{anchor}'")
    return count


def main():
    errors = []
    if not os.path.isfile(os.path.join(SRC, "SUMMARY.md")):
        print(f"check_book_links: no {os.path.relpath(SRC, ROOT)}/SUMMARY.md", file=sys.stderr)
        return 1
    chapters = []
    for d, _, files in os.walk(SRC):
        chapters += [os.path.join(d, f) for f in files if f.endswith(".md")]
    chapters.sort()
    links = sum(check_file(p, True, errors) for p in chapters)
    summary = os.path.join(SRC, "SUMMARY.md")
    listed = {
        os.path.normpath(os.path.join(SRC, unquote(t.partition("#")[0])))
        for _, t in targets(summary)
        if t and not external(t)
    }
    # A file a chapter includes ({{#include perf/NAME.md}}) is part of that chapter.
    included = set()
    for p in chapters:
        for m in re.finditer(r"\{\{#include\s+([^}\s:]+)", open(p, encoding="utf-8").read()):
            included.add(os.path.normpath(os.path.join(os.path.dirname(p), m.group(1))))
    for p in sorted(included):
        if not os.path.isfile(p):
            errors.append(f"{os.path.relpath(p, ROOT)}: included by a chapter, but missing")
    for p in chapters:
        if p != summary and p not in listed and p not in included:
            errors.append(f"{os.path.relpath(p, ROOT)}:1: not listed in docs/src/SUMMARY.md, so mdBook leaves it out")
    readme = os.path.join(ROOT, "README.md")
    if os.path.isfile(readme):
        links += check_file(readme, False, errors)
    for e in errors:
        print(e)
    if errors:
        print(f"check_book_links: {len(errors)} broken of {links} links", file=sys.stderr)
        return 1
    print(f"check_book_links: {links} links in {len(chapters)} chapters and README.md resolve")
    return 0


if __name__ == "__main__":
    sys.exit(main())
