#!/usr/bin/env python3
"""Checks the relative links of Markdown files: each linked file exists, and each
`#anchor` is a heading of the file it points into, by GitHub's rule (lower case; every
character but letters, digits, spaces, '-' and '_' dropped; spaces as '-'; a repeated
heading gets -1, -2, ...). Links and images outside code are checked; http(s), mailto
and other URLs with a scheme are not.

Usage: check_links.py FILE.md...  (prints each broken link; exit status 1 if any)
"""
import os
import re
import sys

FENCE = re.compile(r"^\s*(```|~~~)")
CODE_SPAN = re.compile(r"(`+)(.+?)\1")
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def prose_lines(path):
    """(number, line) of the file's lines outside fenced code, code spans removed."""
    fenced = False
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            if FENCE.match(line):
                fenced = not fenced
                continue
            if not fenced:
                yield n, line.rstrip("\n")


def slug(heading):
    text = CODE_SPAN.sub(lambda m: m.group(2), heading)
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text).strip().lower()
    text = "".join(c for c in text if c.isalnum() or c in " -_")
    return text.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        seen, found = {}, set()
        for _, line in prose_lines(path):
            m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
            if m:
                s = slug(m.group(1))
                k = seen.get(s, 0)
                seen[s] = k + 1
                found.add(s if k == 0 else f"{s}-{k}")
        cache[path] = found
    return cache[path]


def broken(path):
    for n, line in prose_lines(path):
        for m in LINK.finditer(CODE_SPAN.sub("", line)):
            target = m.group(1)
            if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target):
                continue
            file, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(path), file)) if file else path
            if not os.path.exists(dest):
                yield f"{path}:{n}: {target}: no file {dest}"
            elif anchor and dest.endswith(".md") and anchor not in anchors(dest):
                yield f"{path}:{n}: {target}: no heading #{anchor} in {dest}"


def main(paths):
    bad = [b for p in paths for b in broken(p)]
    for b in bad:
        print(b)
    checked = sum(1 for p in paths for _, line in prose_lines(p)
                  for _ in LINK.finditer(CODE_SPAN.sub("", line)))
    print(f"check_links: {checked} links in {len(paths)} file(s), {len(bad)} broken")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
