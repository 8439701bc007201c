#!/usr/bin/env python3
"""Check the relative links of Markdown files: every `[text](target)` and `![alt](target)`
outside code blocks must name an existing file, and a `#fragment` must name a heading of the
target Markdown file (GitHub's anchor rules).

    python3 docs/scripts/check_links.py            # README.md, docs/**/*.md, crates/*/README.md
    python3 docs/scripts/check_links.py FILE.md ...

Prints one line per broken link and exits 1 if there is any.
"""
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")


def strip_code(text):
    """The text without fenced code blocks and inline code spans (line numbers kept)."""
    out, fenced = [], False
    for line in text.split("\n"):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            out.append("")
            continue
        out.append("" if fenced else re.sub(r"`[^`]*`", "``", line))
    return out


def anchor(title):
    title = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", title)  # links keep their text
    title = title.replace("`", "").strip().lower()
    title = re.sub(r"[^\w\- ]", "", title)
    return title.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        found, seen, fenced = set(), {}, False
        for line in path.read_text(encoding="utf-8").split("\n"):
            if line.lstrip().startswith("```"):
                fenced = not fenced
                continue
            m = None if fenced else HEADING.match(line)
            if m:
                a = anchor(m.group(2))
                n = seen.get(a, 0)
                seen[a] = n + 1
                found.add(a if n == 0 else f"{a}-{n}")
        cache[path] = found
    return cache[path]


def check(md):
    bad = []
    for no, line in enumerate(strip_code(md.read_text(encoding="utf-8")), 1):
        for m in LINK.finditer(line):
            target = m.group(1)
            if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
                continue
            path, _, frag = target.partition("#")
            dest = (md.parent / path).resolve() if path else md
            if not dest.exists():
                bad.append(f"{md.relative_to(ROOT)}:{no}: {target}: no such file")
            elif frag and dest.suffix == ".md" and frag not in anchors(dest):
                bad.append(f"{md.relative_to(ROOT)}:{no}: {target}: no heading #{frag}")
    return bad


def main(args):
    if args:
        files = [Path(a).resolve() for a in args]
    else:
        files = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md")),
                 *sorted(ROOT.glob("crates/*/README.md"))]
    bad = [b for f in files for b in check(f)]
    print("\n".join(bad) if bad else f"{len(files)} files, every relative link resolves")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
