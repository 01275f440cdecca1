#!/usr/bin/env python3
"""The counts of issue 32, read off the source tree.

    python3 scripts/house_counts.py            # a table
    python3 scripts/house_counts.py --details  # with the circles and long functions

Counted per crate under crates/*/src:
- import circles: strongly connected groups of two or more files, where a file points at
  another when it names a path in it (`crate::a::b`, `super::x`, `use crate::{..}`).
  A re-export (`pub use`), a `mod` declaration and a `#[cfg(test)]` module (the tests'
  imports, not the file's) are not references.
- functions over 150 lines (from `fn` to its closing brace, comments and strings skipped);
- CLI flag spellings in the core: a kebab-case string given as a parameter name
  (`name: "hankel-factor"`) or backticked in a message;
- options structs (`pub struct *Options`/`*Opts`/`*Config`/`*Request`/`*Settings`) and how
  many are `#[non_exhaustive]`;
- public items of the core reachable by path (`pub fn|struct|enum|trait|type|const|mod`
  not under `pub(crate)` and in a module that is itself public).
"""
import os
import re
import sys
from collections import defaultdict

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
LONG = 150


def strip(text):
    """Comments and string/char literals blanked (newlines kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'r(#*)"', text[i:])
            close = '"' + m.group(1)
            j = text.find(close, i + len(m.group(0)))
            j = n if j < 0 else j + len(close)
            out.append('"' + re.sub(r"[^\n]", " ", text[i + 1:j - 1]) + '"')
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append('"' + re.sub(r"[^\n]", " ", text[i + 1:j]) + '"')
            i = j + 1
        elif c == "'":
            m = re.match(r"'(\\.[^']*|[^\\'])'", text[i:])
            if m:
                out.append(" " * len(m.group(0)))
                i += len(m.group(0))
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def strip_comments_only(text):
    """Line comments dropped (doc comments too); strings kept."""
    return "\n".join(re.sub(r"^\s*//.*$", "", line) for line in text.split("\n"))


def modules(src):
    """file path -> module path tuple, for one crate's src folder."""
    mods = {}
    for dirpath, _, files in os.walk(src):
        for f in files:
            if not f.endswith(".rs"):
                continue
            p = os.path.join(dirpath, f)
            rel = os.path.relpath(p, src)[:-3].split(os.sep)
            if rel[-1] == "mod":
                rel = rel[:-1]
            if rel in (["lib"], ["main"]):
                rel = []
            mods[p] = tuple(rel)
    return mods


def use_paths(tree, prefix=()):
    """Expand a `use` tree (`a::{b, c::d}`) into paths."""
    tree = tree.strip()
    depth = 0
    for k, ch in enumerate(tree):
        if ch == "{":
            if depth == 0:
                head = [s for s in tree[:k].split("::") if s.strip()]
                inner = tree[k + 1:tree.rfind("}")]
                parts, d, start = [], 0, 0
                for m, c2 in enumerate(inner):
                    if c2 == "{":
                        d += 1
                    elif c2 == "}":
                        d -= 1
                    elif c2 == "," and d == 0:
                        parts.append(inner[start:m])
                        start = m + 1
                parts.append(inner[start:])
                res = []
                for part in parts:
                    if part.strip():
                        res += use_paths(part, prefix + tuple(s.strip() for s in head))
                return res
            depth += 1
    segs = [s.strip() for s in tree.split(" as ")[0].split("::") if s.strip()]
    return [prefix + tuple(segs)]


def resolve(path, here, is_mod_file, known):
    """A referenced path, relative to module `here`, to the longest known module."""
    if not path:
        return None
    if path[0] == "crate":
        full = path[1:]
    elif path[0] == "super":
        base = list(here)
        rest = list(path)
        while rest and rest[0] == "super":
            base = base[:-1]
            rest = rest[1:]
        full = tuple(base) + tuple(rest)
    elif path[0] == "self":
        full = tuple(here) + tuple(path[1:])
    else:
        return None
    for k in range(len(full), -1, -1):
        if full[:k] in known:
            return full[:k]
    return None


def graph(src):
    mods = modules(src)
    known = set(mods.values())
    edges = defaultdict(set)
    for p, here in mods.items():
        text = strip(open(p, encoding="utf-8").read())
        # a `#[cfg(test)]` module's imports are the tests', not the file's
        text = re.sub(r"#\[cfg\(test\)\]\s*mod\s+\w+\s*\{.*", "", text, flags=re.S)
        text = re.sub(r"#\[cfg\(test\)\]\s*(pub(\([^)]*\))?\s+)?mod\s+\w+\s*;", "", text)
        is_mod = os.path.basename(p) in ("mod.rs", "lib.rs", "main.rs")
        refs = []
        for m in re.finditer(r"(^|\n)\s*(pub(\([^)]*\))?\s+)?use\s+([^;]+);", text):
            if m.group(2) and m.group(3) is None:
                continue  # pub use: a re-export
            refs += use_paths(m.group(4))
        body = re.sub(r"(^|\n)\s*(pub(\([^)]*\))?\s+)?use\s+[^;]+;", "\n", text)
        for m in re.finditer(r"\b((?:crate|super|self)(?:::[A-Za-z_][A-Za-z0-9_]*)+)", body):
            refs.append(tuple(m.group(1).split("::")))
        for r in refs:
            t = resolve(r, here, is_mod, known)
            if t is not None and t != here:
                edges[here].add(t)
    return mods, edges


def sccs(nodes, edges):
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in nodes:
        if v not in index:
            visit(v)
    return out


def long_functions(src):
    found = []
    for dirpath, _, files in os.walk(src):
        for f in files:
            if not f.endswith(".rs"):
                continue
            p = os.path.join(dirpath, f)
            text = strip(open(p, encoding="utf-8").read())
            for m in re.finditer(r"\bfn\s+([A-Za-z_][A-Za-z0-9_]*)", text):
                # the body's opening brace: the first `{` after the signature at depth 0
                i, depth = m.end(), 0
                while i < len(text):
                    c = text[i]
                    if c in "(<[":
                        depth += 1
                    elif c in ")>]":
                        depth -= 1 if c != ">" or text[i - 1] != "-" else 0
                    elif c == ";" and depth <= 0:
                        i = -1
                        break
                    elif c == "{" and depth <= 0:
                        break
                    i += 1
                if i < 0 or i >= len(text):
                    continue
                d, j = 0, i
                while j < len(text):
                    if text[j] == "{":
                        d += 1
                    elif text[j] == "}":
                        d -= 1
                        if d == 0:
                            break
                    j += 1
                lines = text.count("\n", m.start(), j) + 1
                if lines > LONG:
                    line = text.count("\n", 0, m.start()) + 1
                    found.append((lines, os.path.relpath(p, ROOT), line, m.group(1)))
    return sorted(found, reverse=True)


def cli_flags():
    """The CLI's long flags, from the clap structs under crates/era-cli/src/args."""
    flags = set()
    args = os.path.join(ROOT, "crates", "era-cli", "src", "args")
    for f in os.listdir(args) if os.path.isdir(args) else []:
        text = open(os.path.join(args, f), encoding="utf-8").read()
        for m in re.finditer(r"#\[arg\(([^\]]*)\)\]\s*(?:///[^\n]*\n\s*)*pub (\w+):", text):
            if "long" in m.group(1):
                named = re.search(r'long\s*=\s*"([^"]+)"', m.group(1))
                flags.add(named.group(1) if named else m.group(2).replace("_", "-"))
    return {f for f in flags if "-" in f}


def flag_spellings(src):
    """Kebab-case flag names in the core's code: as a parameter name, backticked with its
    dashes in a message, or any string literal that is one of the CLI's flags. The value
    names of an enum's `named!` table are the core's own words (what model.json writes,
    what `FromStr` parses), not flags, even where a switch is named after one
    (`Realizer::EraDc => "era-dc"` and `--era-dc`); they are not counted as literals."""
    flags = cli_flags()
    hits = []
    for dirpath, _, files in os.walk(src):
        for f in files:
            if not f.endswith(".rs"):
                continue
            p = os.path.join(dirpath, f)
            in_table = False
            for k, line in enumerate(strip_comments_only(open(p, encoding="utf-8").read()).split("\n"), 1):
                if "named!(" in line:
                    in_table = True
                value_name = in_table and re.fullmatch(r'\s*[\w:]+\s*=>\s*"[a-z0-9-]+",?\s*', line)
                if in_table and "]);" in line:
                    in_table = False
                literals = set() if value_name else set(re.findall(r'"([a-z0-9]+(?:-[a-z0-9]+)+)"', line))
                if (re.search(r'name:\s*"[a-z0-9]+(-[a-z0-9]+)+"', line)
                        or re.search(r"`--[a-z]", line) or literals & flags):
                    hits.append(f"{os.path.relpath(p, ROOT)}:{k}: {line.strip()[:100]}")
    return hits


def options_structs(src):
    total, marked, names = 0, 0, []
    for dirpath, _, files in os.walk(src):
        for f in files:
            if not f.endswith(".rs"):
                continue
            text = open(os.path.join(dirpath, f), encoding="utf-8").read()
            for m in re.finditer(r"((?:#\[[^\]]*\]\s*)*)pub struct (\w*(?:Options|Opts|Config|Request|Settings|Criteria))\b", text):
                total += 1
                ok = "non_exhaustive" in m.group(1)
                marked += ok
                if not ok:
                    names.append(m.group(2))
    return total, marked, names


def public_items(src):
    mods = modules(src)
    private_mods = set()
    for p, here in mods.items():
        text = strip(open(p, encoding="utf-8").read())
        for m in re.finditer(r"(^|\n)\s*(pub(\([^)]*\))?\s+)?mod\s+(\w+)\s*;", text):
            if not m.group(2) or m.group(3):
                private_mods.add(here + (m.group(4),))
    count = 0
    for p, here in mods.items():
        if any(here[:k] in private_mods for k in range(1, len(here) + 1)):
            continue
        text = strip(open(p, encoding="utf-8").read())
        # items inside `#[cfg(test)] mod tests` are not public
        cut = re.search(r"#\[cfg\(test\)\]\s*mod\s+\w+\s*\{", text)
        if cut:
            text = text[:cut.start()]
        count += len(re.findall(r"(^|\n)\s*pub\s+(unsafe\s+)?(async\s+)?(const\s+)?(fn|struct|enum|trait|type|const|static|mod)\s", text))
    return count


def main():
    details = "--details" in sys.argv
    print(f"{'crate':10} {'files':>5} {'circles':>7} {'fn>150':>6} {'pub items':>9}")
    for crate in sorted(os.listdir(os.path.join(ROOT, "crates"))):
        src = os.path.join(ROOT, "crates", crate, "src")
        if not os.path.isdir(src):
            continue
        mods, edges = graph(src)
        circles = sccs(sorted(set(mods.values())), edges)
        longs = long_functions(src)
        pub = public_items(src) if crate == "era" else "-"
        print(f"{crate:10} {len(mods):5} {len(circles):7} {len(longs):6} {pub:>9}")
        if details:
            for c in circles:
                print("   circle:", " ↔ ".join("::".join(x) or "(root)" for x in c))
            for n, p, line, name in longs:
                print(f"   {n:4} lines  {name}  {p}:{line}")
    core = os.path.join(ROOT, "crates", "era", "src")
    flags = flag_spellings(core)
    total, marked, names = options_structs(core)
    print(f"CLI flag spellings in the core: {len(flags)}")
    if details:
        for h in flags:
            print("   ", h)
    print(f"core options structs: {total}, #[non_exhaustive]: {marked}")
    if details and names:
        print("   not marked:", ", ".join(sorted(names)))
    top = sorted(e for e in os.listdir(core))
    print(f"core top level: {len(top)} entries: {' '.join(top)}")
    readme = sum(1 for _ in open(os.path.join(ROOT, "README.md"), encoding="utf-8"))
    print(f"README.md: {readme} lines")


if __name__ == "__main__":
    main()
